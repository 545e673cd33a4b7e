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
//! Boxes are axis-aligned: they translate, they do not spin (refused). Keyframes hold
//! offsets, not rotations. Pinned cloth vertices move by the same motions in `[[pins]]`
//! groups (`crate::pins`), where a spin turns them about a pivot.

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

/// A keyframe: the collider's offset from its placed position at time `t`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Key {
    /// Time, s (≥ 0; keys strictly increasing).
    pub t: f32,
    /// Offset, m.
    pub offset: [f32; 3],
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
    /// Angular velocity about the centre, rad/s.
    pub spin: [f32; 3],
}

fn norm(a: [f32; 3]) -> f32 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

impl Motion {
    /// Whether it moves the collider's surface at all.
    pub fn is_still(&self) -> bool {
        self.velocity == [0.0; 3] && self.spin == [0.0; 3] && self.keys.iter().all(|k| k.offset == self.keys[0].offset)
    }

    /// The pose at time `t`, s.
    pub fn at(&self, t: f64) -> Pose {
        let (mut offset, mut vel) = ([0.0f64; 3], [0.0f64; 3]);
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
        }
        let f = |k: usize| [offset[k] + self.velocity[k] as f64 * t, vel[k] + self.velocity[k] as f64];
        let (x, y, z) = (f(0), f(1), f(2));
        Pose {
            offset: [x[0] as f32, y[0] as f32, z[0] as f32],
            velocity: [x[1] as f32, y[1] as f32, z[1] as f32],
            spin: self.spin,
        }
    }

    /// The fastest its centre moves, m/s (keyframes at their segments' peak speed).
    pub fn max_speed(&self) -> f32 {
        let peak = match self.ease {
            Ease::Linear => 1.0,
            Ease::Smooth => 1.5,
        };
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
        let speed = self.max_speed() + norm(self.spin) * size;
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
            keys: vec![Key { t: 1.0, offset: [0.0; 3] }, Key { t: 3.0, offset: [2.0, 0.0, 0.0] }],
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
                Motion {
                    keys: vec![Key { t: 1.0, offset: [0.0; 3] }, Key { t: 1.0, offset: [1.0; 3] }],
                    ..Motion::default()
                },
                true,
                "strictly increasing",
            ),
            (Motion { spin: [0.0, 1.0, 0.0], ..Motion::default() }, false, "not turn"),
            (
                Motion { repeat: Repeat::Loop, keys: vec![Key { t: 0.0, offset: [0.0; 3] }], ..Motion::default() },
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
}
