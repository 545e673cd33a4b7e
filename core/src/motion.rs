//! Colliders that move: a constant velocity, a spin (spheres), keyframed offsets.
//!
//! A collider's motion is an offset from where the scene places it, a function of the
//! simulated time `t` (seconds since the start or the last reset):
//!
//! `offset(t) = velocity · t + keys(t)`
//!
//! with `keys(t)` interpolated between keyframes `(t, offset)` (linearly or smoothly,
//! once or looping). A sphere may also spin about its centre (`spin`, rad/s): it stays
//! where it is, but its surface moves at `spin × (x − centre)`. The solvers evaluate every
//! collider at the start of every substep ([`crate::Scene::colliders_at`]) and give the
//! contacts the surface's velocity there: the normal velocity into the surface and the
//! friction act on the particle's velocity *relative to the surface*, so a collider
//! pushes the cloth, and friction drags it along.
//!
//! A fast collider is not swept: a scene is refused where a collider moves more than half
//! its radius (a box: half its smallest half-extent) in one substep
//! ([`Motion::check_speed`]); below that, a particle it overtakes within a substep is
//! still in its front half, and is pushed out forward.
//!
//! In a scene file, a `motion` table on a sphere or a box:
//!
//! ```toml
//! [[spheres]]
//! center = [0, 0.5, 0]
//! radius = 0.4
//! motion = { spin = [0, 3, 0] }                      # rad/s about the centre
//!
//! [[boxes]]
//! min = [-0.5, 0, -0.5]
//! max = [0.5, 0.8, 0.5]
//! motion = { velocity = [1.5, 0, 0] }                # m/s, from t = 0
//! # or keyframes: offsets from the placed box at times t (s), strictly increasing
//! # motion = { keys = [{ t = 0, offset = [0, 0, 0] }, { t = 1, offset = [2, 0, 0] }],
//! #            ease = "smooth", repeat = "loop" }
//! ```
//!
//! Boxes are axis-aligned: they translate, they do not spin (refused). A key may also turn
//! the collider (`rotate_deg`, degrees about x, then y, then z: interpolated along the
//! shorter arc, eased as the offsets, its angular velocity given to the contacts) — a
//! sphere's surface then moves as with a spin, a body (`crate::sdf`) turns about its
//! pivot; a motion turns by a constant spin or by keys, not both. Pinned cloth vertices
//! move by the same motions in `[[pins]]` groups (`crate::pins`), turned about a pivot.

use serde::{Deserialize, Serialize};

use crate::params::{ParamError, finite_in};

/// How a keyframed motion passes between two keys.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Ease {
    /// At constant speed between keys (the speed jumps at a key).
    #[default]
    Linear,
    /// Smoothstep: starting and stopping at every key (3u² − 2u³; its speed peaks at 1.5×
    /// the segment's mean).
    Smooth,
}

/// What a keyframed motion does after its last key.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Repeat {
    /// Stays at the last key.
    #[default]
    Once,
    /// Starts again from the first key (the last key's offset should equal the first's
    /// for a motion without a jump).
    Loop,
}

/// A keyframe: the collider's offset from its placed position at time `t`, and its turn.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Key {
    /// Time, s (≥ 0; keys strictly increasing).
    pub t: f32,
    /// Offset, m.
    pub offset: [f32; 3],
    /// Turn about the centre (a sphere's) or pivot (a body's, a pin group's), degrees about
    /// x, then y, then z, as a placement's `rotate_deg`; default none. Between keys the
    /// turn is interpolated along the shorter arc (slerp, eased as the offsets).
    #[serde(default)]
    pub rotate_deg: [f32; 3],
}

impl Key {
    /// A key of an offset only.
    pub const fn new(t: f32, offset: [f32; 3]) -> Self {
        Self { t, offset, rotate_deg: [0.0; 3] }
    }

    /// Its turn as a quaternion (f64).
    pub fn rotation(&self) -> glam::DQuat {
        let [rx, ry, rz] = self.rotate_deg.map(|d| (d as f64).to_radians());
        glam::DQuat::from_euler(glam::EulerRot::ZYX, rz, ry, rx)
    }
}

/// A collider's motion (see the module's documentation).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Motion {
    /// Constant velocity, m/s.
    pub velocity: [f32; 3],
    /// Angular velocity about the centre, rad/s (spheres only).
    pub spin: [f32; 3],
    /// Keyframed offsets (none: no keyframed part).
    pub keys: Vec<Key>,
    /// Interpolation between keys.
    pub ease: Ease,
    /// After the last key.
    pub repeat: Repeat,
}

/// Where a moving collider is at a time: its offset and its velocity.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Pose {
    /// Offset from the placed position, m.
    pub offset: [f32; 3],
    /// Velocity of the collider's centre, m/s.
    pub velocity: [f32; 3],
    /// Angular velocity about the centre, rad/s (the constant spin's or the keys' turn's).
    pub spin: [f32; 3],
    /// The turn at this time (the spin's by `spin·t`, or the keys'), a unit quaternion.
    pub rotation: glam::DQuat,
}

fn norm(a: [f32; 3]) -> f32 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

impl Motion {
    /// Whether it moves the collider's surface at all.
    pub fn is_still(&self) -> bool {
        self.velocity == [0.0; 3]
            && self.spin == [0.0; 3]
            && self.keys.iter().all(|k| k.offset == self.keys[0].offset && k.rotate_deg == self.keys[0].rotate_deg)
    }

    /// Whether its keys turn (a rotation in any key).
    pub fn keys_turn(&self) -> bool {
        self.keys.iter().any(|k| k.rotate_deg != [0.0; 3])
    }

    /// The pose at time `t`, s.
    pub fn at(&self, t: f64) -> Pose {
        let (mut offset, mut vel) = ([0.0f64; 3], [0.0f64; 3]);
        // The constant spin's turn, or the keys' (never both: `check`).
        let w = glam::DVec3::from(self.spin.map(f64::from));
        let (mut rotation, mut omega) = if w.length() > 0.0 {
            (glam::DQuat::from_axis_angle(w.normalize(), w.length() * t), w)
        } else {
            (glam::DQuat::IDENTITY, glam::DVec3::ZERO)
        };
        if let (Some(first), Some(last)) = (self.keys.first(), self.keys.last()) {
            let (t0, t1) = (first.t as f64, last.t as f64);
            let tau = match self.repeat {
                Repeat::Loop if t1 > t0 && t > t0 => t0 + (t - t0).rem_euclid(t1 - t0),
                _ => t.clamp(t0, t1),
            };
            // The segment [a, b] holding tau (the last one at its end).
            let i = self.keys.windows(2).position(|w| tau < w[1].t as f64).unwrap_or(self.keys.len().saturating_sub(2));
            let a = self.keys[i];
            let b = *self.keys.get(i + 1).unwrap_or(&a);
            let span = b.t as f64 - a.t as f64;
            let (w, dw) = if span > 0.0 {
                let u = ((tau - a.t as f64) / span).clamp(0.0, 1.0);
                let moving = t >= t0 && (self.repeat == Repeat::Loop || t < t1);
                let rate = if moving { 1.0 / span } else { 0.0 };
                match self.ease {
                    Ease::Linear => (u, rate),
                    Ease::Smooth => (u * u * (3.0 - 2.0 * u), 6.0 * u * (1.0 - u) * rate),
                }
            } else {
                (0.0, 0.0)
            };
            for k in 0..3 {
                let d = b.offset[k] as f64 - a.offset[k] as f64;
                offset[k] = a.offset[k] as f64 + d * w;
                vel[k] = d * dw;
            }
            if self.keys_turn() {
                // q(u) = q_a (q_a⁻¹ q_b)^u along the shorter arc; its angular velocity is
                // R(q_a)·axis·θ·du/dt (the relative turn's axis is fixed by its own turn).
                let (qa, qb) = (a.rotation(), b.rotation());
                let mut rel = qa.inverse() * qb;
                if rel.w < 0.0 {
                    rel = -rel;
                }
                let (axis, angle) = rel.to_axis_angle();
                rotation = (qa * glam::DQuat::from_axis_angle(axis, angle * w)).normalize();
                omega = qa * (axis * (angle * dw));
            }
        }
        let f = |k: usize| [offset[k] + self.velocity[k] as f64 * t, vel[k] + self.velocity[k] as f64];
        let (x, y, z) = (f(0), f(1), f(2));
        Pose {
            offset: [x[0] as f32, y[0] as f32, z[0] as f32],
            velocity: [x[1] as f32, y[1] as f32, z[1] as f32],
            spin: omega.as_vec3().to_array(),
            rotation,
        }
    }

    /// The fastest it turns, rad/s (keyframes at their segments' peak rate).
    pub fn max_turn_rate(&self) -> f32 {
        let peak = self.peak();
        let keys = self
            .keys
            .windows(2)
            .map(|w| {
                let mut rel = w[0].rotation().inverse() * w[1].rotation();
                if rel.w < 0.0 {
                    rel = -rel;
                }
                (rel.to_axis_angle().1 / (w[1].t - w[0].t) as f64) as f32 * peak
            })
            .fold(0.0f32, f32::max);
        norm(self.spin) + keys
    }

    /// A segment's peak rate over its mean: 1 linear, 1.5 smooth (smoothstep's slope).
    fn peak(&self) -> f32 {
        match self.ease {
            Ease::Linear => 1.0,
            Ease::Smooth => 1.5,
        }
    }

    /// The fastest its centre moves, m/s (keyframes at their segments' peak speed).
    pub fn max_speed(&self) -> f32 {
        let peak = self.peak();
        let keys = self
            .keys
            .windows(2)
            .map(|w| {
                let d =
                    [w[1].offset[0] - w[0].offset[0], w[1].offset[1] - w[0].offset[1], w[1].offset[2] - w[0].offset[2]];
                norm(d) / (w[1].t - w[0].t) * peak
            })
            .fold(0.0f32, f32::max);
        norm(self.velocity) + keys
    }

    /// Checks the motion of the collider at `field` (`spheres[0]`): finite, keys in order.
    pub fn check(&self, field: &str, can_spin: bool) -> Result<(), ParamError> {
        let at = |what: &str| format!("{field}.motion.{what}");
        for v in self.velocity {
            finite_in(at("velocity"), v, -1e3, 1e3)?;
        }
        for v in self.spin {
            finite_in(at("spin"), v, -1e4, 1e4)?;
        }
        if !can_spin && self.spin != [0.0; 3] {
            return Err(ParamError::new(
                at("spin"),
                format!("{:?}", self.spin),
                "a box is axis-aligned: it can move, not turn (spin is for spheres)",
            ));
        }
        if let Some(i) = self.keys.iter().position(|k| k.rotate_deg != [0.0; 3]) {
            let field = at(&format!("keys[{i}].rotate_deg"));
            for v in self.keys[i].rotate_deg {
                finite_in(field.clone(), v, -3600.0, 3600.0)?;
            }
            if !can_spin {
                return Err(ParamError::new(
                    field,
                    format!("{:?}", self.keys[i].rotate_deg),
                    "a box is axis-aligned: it can move, not turn",
                ));
            }
            if self.spin != [0.0; 3] {
                return Err(ParamError::new(
                    field,
                    format!("{:?}", self.keys[i].rotate_deg),
                    "turn by a constant spin or by keys, not both",
                ));
            }
        }
        for (i, k) in self.keys.iter().enumerate() {
            for v in k.rotate_deg {
                finite_in(at(&format!("keys[{i}].rotate_deg")), v, -3600.0, 3600.0)?;
            }
        }
        for (i, k) in self.keys.iter().enumerate() {
            finite_in(at(&format!("keys[{i}].t")), k.t, 0.0, 1e6)?;
            for v in k.offset {
                finite_in(at(&format!("keys[{i}].offset")), v, -1e4, 1e4)?;
            }
            if i > 0 && k.t <= self.keys[i - 1].t {
                return Err(ParamError::new(
                    at(&format!("keys[{i}].t")),
                    k.t,
                    format!(
                        "keys must be in strictly increasing time (the key before is at t = {})",
                        self.keys[i - 1].t
                    ),
                ));
            }
        }
        if self.repeat == Repeat::Loop && self.keys.len() < 2 {
            return Err(ParamError::new(at("repeat"), "\"loop\"", "a looping motion needs at least two keys"));
        }
        Ok(())
    }

    /// Refuses a motion faster than a substep of `dt` s resolves for a collider of
    /// `size` m (a sphere's radius, a box's smallest half-extent): its surface may move
    /// at most half of `size` per substep (see the module's documentation).
    pub fn check_speed(&self, field: &str, size: f32, dt: f32) -> Result<(), ParamError> {
        let speed = self.max_speed() + self.max_turn_rate() * size;
        let step = speed * dt;
        if step > 0.5 * size {
            return Err(ParamError::new(
                format!("{field}.motion"),
                format!("{speed} m/s"),
                format!(
                    "moves {step:.3} m per substep of {dt:.5} s at its fastest; a substep resolves at most half its size ({:.3} m): slow it or raise params.substeps",
                    0.5 * size
                ),
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn keys(ease: Ease, repeat: Repeat) -> Motion {
        Motion {
            keys: vec![Key::new(1.0, [0.0; 3]), Key::new(3.0, [2.0, 0.0, 0.0])],
            ease,
            repeat,
            ..Motion::default()
        }
    }

    #[test]
    fn keys_interpolate_hold_and_loop_with_the_speed_of_their_segment() {
        // Exact in f64 then rounded once to f32: bounds of a few f32 ulps at these sizes.
        let m = keys(Ease::Linear, Repeat::Once);
        assert_eq!(m.at(0.5).offset, [0.0; 3], "before the first key: its offset");
        assert_eq!(m.at(0.5).velocity, [0.0; 3]);
        assert!((m.at(2.0).offset[0] - 1.0).abs() < 1e-6 && (m.at(2.0).velocity[0] - 1.0).abs() < 1e-6);
        assert_eq!(m.at(5.0).offset[0], 2.0, "after the last key: held there");
        assert_eq!(m.at(5.0).velocity[0], 0.0);
        let l = keys(Ease::Linear, Repeat::Loop);
        assert!((l.at(4.0).offset[0] - 1.0).abs() < 1e-6, "t = 4 is t = 2 of the loop: {:?}", l.at(4.0));
        let s = keys(Ease::Smooth, Repeat::Once);
        // Smoothstep: halfway at the middle, speed 1.5× the mean there, 0 at the keys.
        assert!((s.at(2.0).offset[0] - 1.0).abs() < 1e-6 && (s.at(2.0).velocity[0] - 1.5).abs() < 1e-6);
        assert!(s.at(1.0).velocity[0].abs() < 1e-6);
        assert!((s.max_speed() - 1.5).abs() < 1e-6);
        // A constant velocity adds to the keys.
        let v = Motion { velocity: [0.0, 0.0, 2.0], ..keys(Ease::Linear, Repeat::Once) };
        assert!((v.at(2.0).offset[2] - 4.0).abs() < 1e-6 && (v.at(2.0).velocity[2] - 2.0).abs() < 1e-6);
    }

    #[test]
    fn removing_a_collider_drops_its_motion_and_renumbers_the_rest() {
        use crate::scene::{ColliderId as C, Scene};
        let mut s = Scene::default(); // three spheres
        let m = |x: f32| Motion { velocity: [x, 0.0, 0.0], ..Motion::default() };
        s.motions = vec![(C::Sphere(0), m(1.0)), (C::Sphere(1), m(2.0)), (C::Sphere(2), m(3.0))];
        s.remove_collider(C::Sphere(1));
        assert_eq!(s.spheres.len(), 2);
        assert_eq!(s.motions, vec![(C::Sphere(0), m(1.0)), (C::Sphere(1), m(3.0))]);
        assert!(s.validate().is_ok());
        s.remove_collider(C::Box(0)); // none: nothing changes
        assert_eq!(s.motions.len(), 2);
    }

    #[test]
    fn bad_motions_are_refused_naming_the_field() {
        let cases: [(Motion, bool, &str); 4] = [
            (Motion { velocity: [f32::NAN, 0.0, 0.0], ..Motion::default() }, true, "s[0].motion.velocity"),
            (
                Motion { keys: vec![Key::new(1.0, [0.0; 3]), Key::new(1.0, [1.0; 3])], ..Motion::default() },
                true,
                "strictly increasing",
            ),
            (Motion { spin: [0.0, 1.0, 0.0], ..Motion::default() }, false, "not turn"),
            (
                Motion { repeat: Repeat::Loop, keys: vec![Key::new(0.0, [0.0; 3])], ..Motion::default() },
                true,
                "two keys",
            ),
        ];
        for (m, can_spin, expect) in cases {
            let e = m.check("s[0]", can_spin).expect_err(expect).to_string();
            assert!(e.contains(expect), "{e}");
        }
        // 10 m/s with substeps of 1/960 s: 0.0104 m a substep; a sphere of 0.02 m resolves
        // 0.01 m (refused), one of 0.03 m 0.015 m.
        let fast = Motion { velocity: [10.0, 0.0, 0.0], ..Motion::default() };
        let e = fast.check_speed("s[0]", 0.02, 1.0 / 960.0).unwrap_err().to_string();
        assert!(e.contains("per substep") && e.contains("s[0].motion"), "{e}");
        assert!(fast.check_speed("s[0]", 0.03, 1.0 / 960.0).is_ok());
    }

    fn turning(ease: Ease) -> Motion {
        Motion {
            keys: vec![Key::new(0.0, [0.0; 3]), Key { rotate_deg: [0.0, 90.0, 0.0], ..Key::new(1.0, [0.0; 3]) }],
            ease,
            ..Motion::default()
        }
    }

    #[test]
    fn keys_turn_along_the_shorter_arc_at_the_rate_of_their_angle() {
        use std::f64::consts::FRAC_PI_2;
        // 0 → 90° about y in 1 s, linear: half way at 0.5 s, at π/2 rad/s throughout
        // (to the f64 quaternion's rounding: 1e-9), still before and after.
        let m = turning(Ease::Linear);
        assert!(!m.is_still() && m.keys_turn());
        let p = m.at(0.5);
        let (axis, angle) = p.rotation.to_axis_angle();
        assert!((angle - FRAC_PI_2 / 2.0).abs() < 1e-9 && (axis.y - 1.0).abs() < 1e-9, "{axis} {angle}");
        assert!((p.spin[1] as f64 - FRAC_PI_2).abs() < 1e-6 && p.spin[0] == 0.0 && p.spin[2] == 0.0, "{:?}", p.spin);
        assert_eq!(m.at(2.0).spin, [0.0; 3]);
        assert!((m.at(2.0).rotation.to_axis_angle().1 - FRAC_PI_2).abs() < 1e-9);
        // Smooth: the rate peaks at 1.5× the mean mid-way, 0 at the keys.
        let s = turning(Ease::Smooth);
        assert!((s.at(0.5).spin[1] as f64 - 1.5 * FRAC_PI_2).abs() < 1e-6);
        assert!(s.at(0.0).spin[1].abs() < 1e-9);
        assert!((s.max_turn_rate() as f64 - 1.5 * FRAC_PI_2).abs() < 1e-6);
        // A turn about all three axes: the angular velocity is the rotation's derivative,
        // (q(t + ε) q(t)⁻¹ as axis·angle) / ε, to the difference's O(ε) (1e-5 rad/s).
        let m = Motion {
            keys: vec![
                Key { rotate_deg: [10.0, -20.0, 5.0], ..Key::new(0.0, [0.0; 3]) },
                Key { rotate_deg: [-40.0, 60.0, 30.0], ..Key::new(0.7, [0.0; 3]) },
            ],
            ease: Ease::Smooth,
            ..Motion::default()
        };
        for t in [0.1, 0.35, 0.6] {
            let eps = 1e-6;
            let (q0, q1) = (m.at(t - eps).rotation, m.at(t + eps).rotation);
            let (axis, angle) = (q1 * q0.inverse()).to_axis_angle();
            let fd = axis * (angle / (2.0 * eps));
            let w = glam::DVec3::from(m.at(t).spin.map(f64::from));
            assert!((fd - w).length() < 1e-5, "t {t}: ω {w} vs the derivative {fd}");
        }
    }

    #[test]
    fn turning_keys_are_refused_on_boxes_with_a_spin_and_when_not_finite() {
        let e = turning(Ease::Linear).check("boxes[0]", false).unwrap_err().to_string();
        assert!(e.contains("boxes[0].motion.keys[1].rotate_deg") && e.contains("axis-aligned"), "{e}");
        let both = Motion { spin: [0.0, 1.0, 0.0], ..turning(Ease::Linear) };
        let e = both.check("bodies[0]", true).unwrap_err().to_string();
        assert!(e.contains("not both"), "{e}");
        let mut nan = turning(Ease::Linear);
        nan.keys[1].rotate_deg[2] = f32::NAN;
        let e = nan.check("spheres[0]", true).unwrap_err().to_string();
        assert!(e.contains("rotate_deg") && e.contains("finite"), "{e}");
        // A sphere of 0.1 m turned 90° in 1 ms: its surface moves 0.16 m per substep.
        let fast = Motion {
            keys: vec![Key::new(0.0, [0.0; 3]), Key { rotate_deg: [90.0, 0.0, 0.0], ..Key::new(0.001, [0.0; 3]) }],
            ..Motion::default()
        };
        assert!(fast.check_speed("spheres[0]", 0.1, 1e-3).is_err());
    }
}
