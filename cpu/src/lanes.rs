//! A structure-of-arrays copy of the particle state for the SIMD fast paths.
//!
//! The kernels' buffers hold `[x, y, z, w]` per particle (the GPU layout). A SIMD lane
//! group wants eight x's in a row; gathering them from `[f32; 4]`s costs a transpose at
//! every neighbour read (12 per particle in `springs`), which measured slower than the
//! arithmetic. So each substep transposes once into these arrays and the fast paths read
//! contiguous lanes. Pure data movement: the results stay bit-identical to the twins.

use rayon::prelude::*;
use wide::f32x8;

use super::{Exec, LANES};
use clothlab_core::grid::V4;

/// Component arrays of the positions and of the velocities.
#[derive(Debug, Clone, Default)]
pub struct Lanes {
    /// x, y, z, w of the positions.
    pub pos: [Vec<f32>; 4],
    /// x, y, z of the velocities.
    pub vel: [Vec<f32>; 3],
}

impl Lanes {
    /// Fills `pos` from `src` (and `vel` from `vel` when it is given).
    pub fn fill(&mut self, exec: Exec, n: usize, src: &[V4], vel: Option<&[V4]>) {
        let np = src.len();
        for v in self.pos.iter_mut().chain(self.vel.iter_mut()) {
            v.resize(np, 0.0);
        }
        let [px, py, pz, pw] = &mut self.pos;
        let [vx, vy, vz] = &mut self.vel;
        let row = |j: usize, (((px, py), (pz, pw)), ((vx, vy), vz)): RowMut| {
            for i in 0..px.len() {
                let a = src[j * n + i];
                px[i] = a[0];
                py[i] = a[1];
                pz[i] = a[2];
                pw[i] = a[3];
                if let Some(vel) = vel {
                    let b = vel[j * n + i];
                    vx[i] = b[0];
                    vy[i] = b[1];
                    vz[i] = b[2];
                }
            }
        };
        match exec {
            Exec::Serial => px
                .chunks_mut(n)
                .zip(py.chunks_mut(n))
                .zip(pz.chunks_mut(n).zip(pw.chunks_mut(n)))
                .zip(vx.chunks_mut(n).zip(vy.chunks_mut(n)).zip(vz.chunks_mut(n)))
                .enumerate()
                .for_each(|(j, r)| row(j, r)),
            Exec::Parallel => px
                .par_chunks_mut(n)
                .zip(py.par_chunks_mut(n))
                .zip(pz.par_chunks_mut(n).zip(pw.par_chunks_mut(n)))
                .zip(vx.par_chunks_mut(n).zip(vy.par_chunks_mut(n)).zip(vz.par_chunks_mut(n)))
                .enumerate()
                .for_each(|(j, r)| row(j, r)),
        }
    }

    /// x, y, z of the positions `start .. start + LANES`.
    #[inline(always)]
    pub fn pos3(&self, start: usize) -> [f32x8; 3] {
        std::array::from_fn(|c| lane(&self.pos[c], start))
    }

    /// w of the positions `start .. start + LANES`.
    #[inline(always)]
    pub fn w(&self, start: usize) -> f32x8 {
        lane(&self.pos[3], start)
    }

    /// x, y, z of the velocities at `start .. start + LANES`.
    #[inline(always)]
    pub fn vel3(&self, start: usize) -> [f32x8; 3] {
        std::array::from_fn(|c| lane(&self.vel[c], start))
    }
}

type RowMut<'a> =
    (((&'a mut [f32], &'a mut [f32]), (&'a mut [f32], &'a mut [f32])), ((&'a mut [f32], &'a mut [f32]), &'a mut [f32]));

#[inline(always)]
pub(crate) fn lane(v: &[f32], start: usize) -> f32x8 {
    let a: [f32; LANES] = v[start..start + LANES].try_into().expect("LANES elements");
    f32x8::from(a)
}
