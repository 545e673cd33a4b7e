//! Pins that move: groups of held cloth vertices carried by a rigid motion.
//!
//! A scene's `[[pins]]` entry holds every particle whose rest position lies in its box
//! (`min`, `max`; of any cloth, grid or mesh, besides what `cloth.pinning` holds) and moves
//! them with its `motion` (the colliders' [`Motion`]: a constant velocity, keyframed
//! offsets, and a spin — here a real rotation about the group's `pivot`, by default the
//! centre of its particles):
//!
//! `x(t) = pivot + offset(t) + R(t)·(x_rest − pivot)`, `R(t)` the rotation by `spin·t`,
//!
//! `v(t) = velocity(t) + spin × R(t)·(x_rest − pivot)`.
//!
//! ```toml
//! [[pins]]                       # the top edge, turned about the cloth's axis
//! min = [-1.1, 1.9, -1.1]
//! max = [1.1, 2.1, -0.95]
//! motion = { spin = [0, 0, 1.5] }
//! [[pins]]                       # the far edge, pulled away and back
//! min = [-1.1, 1.9, 0.95]
//! max = [1.1, 2.1, 1.1]
//! motion = { keys = [{ t = 0, offset = [0, 0, 0] }, { t = 1, offset = [0, 0, 0.5] }] }
//! ```
//!
//! A particle in two boxes belongs to the first. The host evaluates every group's pose
//! for every substep of a frame ([`frame_poses`]), a GPU solver writes them once per
//! frame, and the `pins` kernel (twin [`drive`]) puts each moving pin at its pose, with
//! the pose's velocity, before the substep's first kernel. Which pose: where the
//! integrator evaluates the cloth ([`at_substep_end`]) — the substep's start for the
//! force-based ones (Verlet, Euler, RK, implicit), its end for the position-based ones
//! (XPBD, VBD), which solve for the state at the end. Every integrator keeps a pinned
//! particle where it is (its `w` is 0), so all eight take moving pins without a change
//! of their own; a frame's last state shows the pins at its last substep's pose (one
//! substep behind the frame's end for the force-based ones).
//!
//! Measured with a curtain carried at constant velocity, which must be the still curtain
//! moved (`tests/tests/suite/pins.rs`): Verlet and implicit to rounding (≤ 9.3e-7 m after
//! 0.5 s); XPBD 1.2e-4 m and VBD 1.7e-4 m (their damping takes a pin's displacement over
//! the substep as 0: it is placed before the prediction); RK4 4.2e-3 m (its later stages
//! see the pins at the substep's start). Moving the pins inside those integrators (a
//! pinned particle advanced by its velocity) is what would remove the last three.
//!
//! Tethers hold each particle within `(1 + strain_limit)` of its nearest pins: a motion
//! that pulls pins apart further than the cloth can stretch (two edges twisted in place)
//! leaves the springs between the halves to take the rest, without bound
//! (`scenes/cloth-twist.toml` says how its motion avoids it).
//!
//! Keyframes may turn a group too (`rotate_deg`, `crate::motion`): `R(t)` is then the keys'
//! turn and `spin` their angular velocity.
//!
//! A group with `scripted = true` is moved by a script (`Sim::set_pin_pose`, Python
//! `set_pin_pose`): each call gives its motion two keys — its pose now and the pose asked
//! for, a frame later — so the pins go there over the next frame at constant speed and
//! hold; every backend drives it from its motion as any moving group's
//! (`Solver::set_pin_motion`). A script moves a group as one rigid body, as a motion does.

use serde::{Deserialize, Serialize};

use crate::motion::Motion;
use crate::params::{Integrator, ParamError, finite_in};

/// A particle's position or velocity as the buffers hold it (`crate::grid::V4`; not
/// imported: grid builds on this module).
type V4 = [f32; 4];

/// At most this many `[[pins]]` groups in a scene (the poses of a substep are a fixed
/// block of this many).
pub const MAX_PIN_GROUPS: usize = 8;

/// A group of pinned particles, and how it moves (see the module's documentation).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PinGroup {
    /// Corner of the box that selects the group's particles by rest position, m.
    pub min: [f32; 3],
    /// The opposite corner, m.
    pub max: [f32; 3],
    /// The point the group turns about, m. Default: the centre of its particles.
    #[serde(default)]
    pub pivot: Option<[f32; 3]>,
    /// Its motion (none: the group is simply held).
    #[serde(default)]
    pub motion: Motion,
    /// Moved by a script (`Sim::set_pin_pose`): its pins are driven every substep, at
    /// their pose (at rest until a script moves them: each pin then `pivot + (rest −
    /// pivot)`, the same to a rounding).
    #[serde(default)]
    pub scripted: bool,
}

impl PinGroup {
    /// Whether `p` lies in the group's box (bounds included).
    pub fn holds(&self, p: [f32; 3]) -> bool {
        (0..3).all(|k| (self.min[k]..=self.max[k]).contains(&p[k]))
    }

    /// Checks group `i` (named `pins[i]`): a finite box with min ≤ max, a finite pivot, a
    /// motion [`Motion::check`] accepts (spin allowed).
    pub fn check(&self, i: usize) -> Result<(), ParamError> {
        for k in 0..3 {
            finite_in(format!("pins[{i}].min"), self.min[k], -1e4, 1e4)?;
            finite_in(format!("pins[{i}].max"), self.max[k], -1e4, 1e4)?;
            if self.max[k] < self.min[k] {
                return Err(ParamError::new(
                    format!("pins[{i}].max"),
                    self.max[k],
                    "every max must be at least its min",
                ));
            }
        }
        for v in self.pivot.into_iter().flatten() {
            finite_in(format!("pins[{i}].pivot"), v, -1e4, 1e4)?;
        }
        self.motion.check(&format!("pins[{i}]"), true)
    }
}

/// Gives group `group` of `groups` a new `motion` (a script's: `Solver::set_pin_motion`),
/// checked as a scene file's; refused for a group the scene does not mark `scripted` (its
/// pins have no slots to drive) and for one out of range.
pub fn set_scripted(groups: &mut [PinGroup], group: usize, motion: Motion) -> Result<(), ParamError> {
    let count = groups.len();
    let Some(g) = groups.get_mut(group) else {
        return Err(ParamError::new("pin group", group, format!("the scene has {count} [[pins]] groups")));
    };
    if !g.scripted {
        return Err(ParamError::new(
            format!("pins[{group}]"),
            "not scripted",
            "a script moves a group the scene marks `scripted = true`",
        ));
    }
    motion.check(&format!("pins[{group}]"), true)?;
    g.motion = motion;
    Ok(())
}

/// One moving pin, as the `pins` kernel reads it (WGSL `PinSlot`, 32 bytes): the
/// particle, its group and its rest position relative to the group's pivot.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct PinSlot {
    /// Rest position minus the group's pivot, m.
    pub rest: [f32; 3],
    /// The particle.
    pub index: u32,
    /// Its `[[pins]]` group.
    pub group: u32,
    /// Padding to 32 bytes.
    pub pad: [u32; 3],
}

/// A group's pose at one substep (WGSL `PinPose`, 96 bytes): `x = R·rest + translation`,
/// `v = velocity + spin × R·rest`; `cols` are R's columns.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct PinPose {
    /// The rotation's columns (w 0).
    pub cols: [[f32; 4]; 3],
    /// Pivot plus the motion's offset, m (w 0).
    pub translation: [f32; 4],
    /// The motion's velocity, m/s (w 0).
    pub velocity: [f32; 4],
    /// The angular velocity, rad/s (w 0).
    pub spin: [f32; 4],
}

impl PinPose {
    /// Elements of `[f32; 4]` (the buffers' `V4`) a pose takes.
    pub const V4S: usize = 6;

    /// The pose of a group about `pivot` moved by `motion`, at time `t`, s.
    pub fn at(motion: &Motion, pivot: [f32; 3], t: f64) -> Self {
        let pose = motion.at(t);
        // The motion's turn (its spin's by spin·t, or its keys'), in f64, rounded once.
        let m = glam::DMat3::from_quat(pose.rotation);
        let r = [m.x_axis.to_array(), m.y_axis.to_array(), m.z_axis.to_array()]; // r[col][row]
        let col = |c: usize| [r[c][0] as f32, r[c][1] as f32, r[c][2] as f32, 0.0];
        let t3 = |k: usize| (pivot[k] as f64 + pose.offset[k] as f64) as f32;
        Self {
            cols: [col(0), col(1), col(2)],
            translation: [t3(0), t3(1), t3(2), 0.0],
            velocity: [pose.velocity[0], pose.velocity[1], pose.velocity[2], 0.0],
            spin: [pose.spin[0], pose.spin[1], pose.spin[2], 0.0],
        }
    }

    /// Where a pin of rest offset `rest` is and how fast it moves: `(x, v)`. The sums run
    /// left to right as the WGSL's do (`(c0·r.x + c1·r.y) + c2·r.z`, then `+ translation`)
    /// so that twin and kernel agree to the bit.
    #[inline(always)]
    pub fn place(&self, rest: [f32; 3]) -> ([f32; 3], [f32; 3]) {
        let c = &self.cols;
        let arm: [f32; 3] = std::array::from_fn(|k| c[0][k] * rest[0] + c[1][k] * rest[1] + c[2][k] * rest[2]);
        let x = std::array::from_fn(|k| arm[k] + self.translation[k]);
        let (v, w) = (self.velocity, self.spin);
        // velocity + spin × arm, left to right as the shaders' surface_vel.
        let v = [
            v[0] + w[1] * arm[2] - w[2] * arm[1],
            v[1] + w[2] * arm[0] - w[0] * arm[2],
            v[2] + w[0] * arm[1] - w[1] * arm[0],
        ];
        (x, v)
    }
}

/// The moving pins of a cloth: the kernel's table, and each group's pivot.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MovingPins {
    /// One slot per pinned particle of a moving group, in particle order.
    pub slots: Vec<PinSlot>,
    /// Each `[[pins]]` group's pivot (the scene's, or the centre of its particles).
    pub pivots: Vec<[f32; 3]>,
}

/// Which particles the scene's `[[pins]]` groups hold (`None`: none of them), from the
/// rest positions `pos`; refuses a group that holds no particle.
pub fn select(groups: &[PinGroup], pos: &[V4]) -> Result<Vec<Option<u32>>, ParamError> {
    let mut of = vec![None; pos.len()];
    for (g, group) in groups.iter().enumerate() {
        let mut any = false;
        for (o, p) in of.iter_mut().zip(pos) {
            if o.is_none() && group.holds([p[0], p[1], p[2]]) {
                *o = Some(g as u32);
                any = true;
            }
        }
        if !any {
            return Err(ParamError::new(
                format!("pins[{g}].min"),
                format!("{:?} .. {:?}", group.min, group.max),
                "the box holds no particle of the cloth at rest (or only ones an earlier group holds)",
            ));
        }
    }
    Ok(of)
}

/// The table of moving pins for particles held as `of` says (see [`select`]), from their
/// rest positions `pos`.
pub fn moving(groups: &[PinGroup], of: &[Option<u32>], pos: &[V4]) -> MovingPins {
    let pivots: Vec<[f32; 3]> = groups
        .iter()
        .enumerate()
        .map(|(g, group)| {
            group.pivot.unwrap_or_else(|| {
                let (mut sum, mut count) = ([0.0f64; 3], 0.0f64);
                for (o, p) in of.iter().zip(pos) {
                    if *o == Some(g as u32) {
                        (0..3).for_each(|k| sum[k] += p[k] as f64);
                        count += 1.0;
                    }
                }
                sum.map(|s| (s / count.max(1.0)) as f32)
            })
        })
        .collect();
    let slots = of
        .iter()
        .zip(pos)
        .enumerate()
        .filter_map(|(i, (o, p))| {
            let g = (*o)? as usize;
            (!groups[g].motion.is_still() || groups[g].scripted).then(|| PinSlot {
                rest: std::array::from_fn(|k| p[k] - pivots[g][k]),
                index: i as u32,
                group: g as u32,
                pad: [0; 3],
            })
        })
        .collect();
    MovingPins { slots, pivots }
}

/// The poses of every group for each substep of a frame starting at `t0` (s) with
/// substeps of `dt`: substep `s`'s block of [`MAX_PIN_GROUPS`] poses (the unused ones the
/// identity) at its end, `t0 + (s + 1)·dt` (summed one `dt` at a time in f64).
pub fn frame_poses(
    groups: &[PinGroup],
    pivots: &[[f32; 3]],
    integrator: Integrator,
    t0: f64,
    dt: f64,
    substeps: u32,
) -> Vec<PinPose> {
    let still = PinPose::at(&Motion::default(), [0.0; 3], 0.0);
    let mut poses = Vec::with_capacity(substeps as usize * MAX_PIN_GROUPS);
    // The time summed substep by substep, as every solver advances its clock.
    let mut t = t0;
    let end = at_substep_end(integrator);
    for _ in 0..substeps {
        let start = t;
        t += dt;
        let at = if end { t } else { start };
        for g in 0..MAX_PIN_GROUPS {
            poses.push(match (groups.get(g), pivots.get(g)) {
                (Some(group), Some(&pivot)) => PinPose::at(&group.motion, pivot, at),
                _ => still,
            });
        }
    }
    poses
}

/// Whether `integrator` takes the pins at the substep's end: the implicit ones (backward
/// Euler, XPBD, VBD) solve for the state at the end, with the pins where they are then;
/// the explicit ones evaluate forces at the start, with the pins where they are then
/// (measured with a cloth carried at constant velocity, which must be the still cloth
/// moved: 5.6e-7 m off with Verlet at the start, 5.7e-3 m at the end; XPBD 1.6e-3 m at the
/// start).
pub fn at_substep_end(integrator: Integrator) -> bool {
    matches!(integrator, Integrator::Xpbd | Integrator::Vbd)
}

/// Each moving pin of `slots` with where its pose for substep `substep` of `poses`
/// ([`frame_poses`]) puts it: `(particle, x, v)`.
pub fn placed<'a>(
    slots: &'a [PinSlot],
    poses: &'a [PinPose],
    substep: u32,
) -> impl Iterator<Item = (usize, [f32; 3], [f32; 3])> + 'a {
    let base = substep as usize * MAX_PIN_GROUPS;
    slots.iter().filter_map(move |s| {
        let (x, v) = poses.get(base + s.group as usize)?.place(s.rest);
        Some((s.index as usize, x, v))
    })
}

/// Puts every moving pin at its pose for substep `substep` of `poses`
/// ([`frame_poses`]): the `pins` kernel's twin.
pub fn drive(slots: &[PinSlot], poses: &[PinPose], substep: u32, pos: &mut [V4], vel: &mut [V4]) {
    for (i, x, v) in placed(slots, poses, substep) {
        if let (Some(p), Some(u)) = (pos.get_mut(i), vel.get_mut(i)) {
            *p = [x[0], x[1], x[2], p[3]];
            *u = [v[0], v[1], v[2], 0.0];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::Key;

    #[test]
    fn a_spinning_group_turns_rigidly_about_its_pivot_at_its_spin() {
        // A quarter turn about +z in 1 s: (1, 0, 0) from the pivot goes to (0, 1, 0) and
        // moves at ω·r = π/2 m/s along −x there. f64 rounded once: a few f32 ulps.
        let m = Motion { spin: [0.0, 0.0, std::f32::consts::FRAC_PI_2], ..Motion::default() };
        let pose = PinPose::at(&m, [1.0, 2.0, 3.0], 1.0);
        let (x, v) = pose.place([1.0, 0.0, 0.0]);
        for (a, b) in x.iter().zip([1.0, 3.0, 3.0]) {
            assert!((a - b).abs() < 1e-6, "{x:?}");
        }
        for (a, b) in v.iter().zip([-std::f32::consts::FRAC_PI_2, 0.0, 0.0]) {
            assert!((a - b).abs() < 1e-6, "{v:?}");
        }
        // Rigid: the distance between two pins is kept at any time (to f32 rounding).
        let pose = PinPose::at(&m, [0.0; 3], 0.37);
        let (a, b) = (pose.place([0.3, -0.2, 0.5]).0, pose.place([-0.4, 0.1, 0.2]).0);
        let d = |p: [f32; 3], q: [f32; 3]| ((0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f32>()).sqrt();
        assert!((d(a, b) - d([0.3, -0.2, 0.5], [-0.4, 0.1, 0.2])).abs() < 1e-6);
    }

    #[test]
    fn groups_select_by_rest_position_the_first_wins_and_an_empty_box_is_refused() {
        let pos: Vec<V4> = (0..4).map(|i| [i as f32, 0.0, 0.0, 1.0]).collect();
        let g = |lo: f32, hi: f32, m: Motion| PinGroup {
            min: [lo, -1.0, -1.0],
            max: [hi, 1.0, 1.0],
            pivot: None,
            motion: m,
            scripted: false,
        };
        let moving_m =
            Motion { keys: vec![Key::new(0.0, [0.0; 3]), Key::new(1.0, [1.0, 0.0, 0.0])], ..Motion::default() };
        let groups = [g(-0.5, 1.5, moving_m.clone()), g(1.0, 2.5, Motion::default())];
        let of = select(&groups, &pos).unwrap();
        assert_eq!(of, vec![Some(0), Some(0), Some(1), None]);
        let m = moving(&groups, &of, &pos);
        assert_eq!(m.pivots, vec![[0.5, 0.0, 0.0], [2.0, 0.0, 0.0]]);
        assert_eq!(m.slots.len(), 2, "only the moving group's pins are driven");
        assert_eq!(m.slots[1].rest, [0.5, 0.0, 0.0]);
        let e = select(&[g(5.0, 6.0, Motion::default())], &pos).unwrap_err().to_string();
        assert!(e.contains("pins[0].min") && e.contains("holds no particle"), "{e}");
        // Halfway through the keys, both pins have moved 0.5 m along x at 1 m/s.
        let poses = frame_poses(&groups, &m.pivots, Integrator::Xpbd, 0.0, 0.25, 2);
        let (mut p, mut v) = (pos.clone(), vec![[0.0; 4]; 4]);
        drive(&m.slots, &poses, 1, &mut p, &mut v);
        assert_eq!((p[0][0], p[1][0], p[2][0]), (0.5, 1.5, 2.0));
        assert_eq!((v[0][0], v[1][0]), (1.0, 1.0));
    }
}
