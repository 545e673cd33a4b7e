//! A mesh's springs: structural along every edge, bending across every interior edge.

use std::collections::HashMap;

use super::{MAX_SPRINGS_PER_VERTEX, MeshError, TriMesh};

/// The springs a mesh gives, with each vertex's slots.
#[derive(Debug, Clone, PartialEq)]
pub struct MeshSprings {
    /// Structural springs: every edge once, `(a, b)` with `a < b`.
    pub edges: Vec<[u32; 2]>,
    /// Bending springs: across every interior edge, between the two vertices opposite it,
    /// `(a, b)` with `a < b`, each pair once and none that is also an edge.
    pub bends: Vec<[u32; 2]>,
    /// Per vertex, its springs in slot order: indices into `edges` then into `bends`
    /// (as `edges.len() + k`); edges first, as many as the vertex has.
    pub slots: Vec<Vec<u32>>,
}

impl MeshSprings {
    /// The springs of `mesh` (whose indices are in range), of any valence; refused only
    /// past [`MAX_SPRINGS_PER_VERTEX`] springs per vertex in all.
    pub fn build(mesh: &TriMesh) -> Result<Self, MeshError> {
        let count = mesh.positions.len();
        // Each undirected edge with the vertices opposite it (one or two).
        let mut opposite: HashMap<(u32, u32), Vec<u32>> = HashMap::with_capacity(3 * mesh.triangles.len());
        for t in &mesh.triangles {
            for e in 0..3 {
                let (a, b, o) = (t[e], t[(e + 1) % 3], t[(e + 2) % 3]);
                opposite.entry((a.min(b), a.max(b))).or_default().push(o);
            }
        }
        let mut edges: Vec<[u32; 2]> = opposite.keys().map(|&(a, b)| [a, b]).collect();
        edges.sort_unstable();
        let edge_set: std::collections::HashSet<[u32; 2]> = edges.iter().copied().collect();
        let mut bends: Vec<[u32; 2]> = opposite
            .values()
            .filter(|o| o.len() == 2 && o[0] != o[1])
            .map(|o| [o[0].min(o[1]), o[0].max(o[1])])
            .filter(|b| !edge_set.contains(b))
            .collect();
        bends.sort_unstable();
        bends.dedup();
        let mut slots: Vec<Vec<u32>> = vec![Vec::new(); count];
        for (k, &[a, b]) in edges.iter().enumerate() {
            slots[a as usize].push(k as u32);
            slots[b as usize].push(k as u32);
        }
        let base = edges.len() as u32;
        for (k, &[a, b]) in bends.iter().enumerate() {
            slots[a as usize].push(base + k as u32);
            slots[b as usize].push(base + k as u32);
        }
        let springs = edges.len() + bends.len();
        if springs > MAX_SPRINGS_PER_VERTEX * count {
            return Err(MeshError::TooManySprings { springs, vertices: count });
        }
        Ok(Self { edges, bends, slots })
    }

    /// The other end of spring `k` (as in `slots`) seen from vertex `v`.
    pub fn other(&self, k: u32, v: u32) -> u32 {
        let [a, b] = self.spring(k);
        if a == v { b } else { a }
    }

    /// Spring `k` (as in `slots`): an edge or a bending spring.
    pub fn spring(&self, k: u32) -> [u32; 2] {
        let k = k as usize;
        if k < self.edges.len() { self.edges[k] } else { self.bends[k - self.edges.len()] }
    }

    /// Whether spring `k` (as in `slots`) is an edge.
    pub fn is_edge(&self, k: u32) -> bool {
        (k as usize) < self.edges.len()
    }
}
