//! Contact geometry, once per collider shape: where a point meets a shape's surface grown
//! by a reach ([`Shape::contact`]: the depth, the outward normal, the surface point and the
//! surface's velocity there) and the ball or box that holds the grown shape
//! ([`Shape::bound`]). Every path that touches colliders calls these: `collide` (the reach
//! is the collision margin; it moves the particle to [`Contact::at`]), VBD's contact
//! energies (the margin and its reach; it uses the depth, normal and velocity), the fused
//! sweep's skip test (the bounds). The WGSL twins of these functions are in
//! `shaders/wgsl/shared/colliders.wgsl` (`sphere_contact`, `box_contact`,
//! `capsule_contact`, `cylinder_contact`, `body_contact`), computed in the same order so
//! that every backend gets the same bits. A new shape is a struct in [`crate::scene`], an
//! `impl Shape` here and its WGSL function (see docs/architecture.md, "A collider shape").

use glam::Vec3;

use crate::scene::{Aabb, Rod, RodKind, Sphere};
use crate::sdf::{SdfHead, sample_grid};

/// A point's contact with a shape's surface grown by a reach.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contact {
    /// How deep inside the grown surface the point is, m (> 0).
    pub depth: f32,
    /// The outward unit normal of the surface there.
    pub n: Vec3,
    /// The point of the grown surface the point leaves to (`collide` moves it there).
    pub at: Vec3,
    /// The surface's velocity at `at`, m/s (`velocity + spin × arm` for a moving shape).
    pub vs: Vec3,
}

/// What holds a shape grown by a reach: the fused sweep tests its SIMD lanes against it
/// before sampling a lane's contacts one by one.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Bound {
    /// Points closer than `r` to `center` (strictly).
    Ball {
        /// Its centre.
        center: Vec3,
        /// Its radius.
        r: f32,
    },
    /// Points strictly between `lo` and `hi`.
    Box {
        /// The lower corner.
        lo: Vec3,
        /// The upper corner.
        hi: Vec3,
    },
}

/// A collider shape's contact geometry.
pub trait Shape {
    /// The contact of a point at `x` inside this shape grown by `reach`, or `None`.
    fn contact(&self, x: Vec3, reach: f32) -> Option<Contact>;
    /// A region holding this shape grown by `reach` (every `x` with a contact lies in it).
    fn bound(&self, reach: f32) -> Bound;
}

/// The velocity `v + ω × arm` of a surface point at `arm` from the centre of a body
/// moving at `v` and spinning at `ω`, added left to right as the shaders' `surface_vel`:
/// `(v.x + ω.y·arm.z) − ω.z·arm.y`, … (Mesa reassociates `v + (p − q)` into that order on
/// the GPU, so it is written so).
#[inline(always)]
pub fn surface_vel(v: Vec3, spin: Vec3, arm: Vec3) -> Vec3 {
    Vec3::new(
        v.x + spin.y * arm.z - spin.z * arm.y,
        v.y + spin.z * arm.x - spin.x * arm.z,
        v.z + spin.x * arm.y - spin.y * arm.x,
    )
}

/// The xyz of a `[f32; 4]`.
#[inline(always)]
fn v3(a: [f32; 4]) -> Vec3 {
    Vec3::new(a[0], a[1], a[2])
}

/// `a·b` summed left to right (the WGSL's `dot3`).
#[inline(always)]
pub(crate) fn dot3(a: Vec3, b: Vec3) -> f32 {
    a.x * b.x + a.y * b.y + a.z * b.z
}

/// A direction away from a centre `d` long `dist`, or up where the point is at the centre.
#[inline(always)]
fn away(d: Vec3, dist: f32) -> Vec3 {
    if dist > 1e-12 { d / dist } else { Vec3::Y }
}

/// The floor at height `y`: still, its normal up.
#[inline(always)]
pub fn floor_contact(y: f32, x: Vec3, reach: f32) -> Option<Contact> {
    let top = y + reach;
    (x.y < top).then(|| Contact { depth: top - x.y, n: Vec3::Y, at: Vec3::new(x.x, top, x.z), vs: Vec3::ZERO })
}

impl Shape for Sphere {
    #[inline(always)]
    fn contact(&self, x: Vec3, reach: f32) -> Option<Contact> {
        let c = Vec3::from(self.center);
        let r = self.radius + reach;
        let d = x - c;
        let dist2 = d.length_squared();
        if dist2 >= r * r {
            return None;
        }
        let dist = dist2.sqrt();
        let n = away(d, dist);
        let arm = n * r;
        Some(Contact { depth: r - dist, n, at: c + arm, vs: surface_vel(v3(self.velocity), v3(self.spin), arm) })
    }

    #[inline(always)]
    fn bound(&self, reach: f32) -> Bound {
        Bound::Ball { center: Vec3::from(self.center), r: self.radius + reach }
    }
}

impl Shape for Aabb {
    #[inline(always)]
    fn contact(&self, x: Vec3, reach: f32) -> Option<Contact> {
        let (lo, hi) = grown(self, reach);
        if !(x.cmpgt(lo).all() && x.cmplt(hi).all()) {
            return None;
        }
        // Leave through the nearest face.
        let (below, above) = (x - lo, hi - x);
        let (mut depth, mut n, mut face) = (below.x, -Vec3::X, lo.x);
        for (d, nn, f) in [
            (above.x, Vec3::X, hi.x),
            (below.y, -Vec3::Y, lo.y),
            (above.y, Vec3::Y, hi.y),
            (below.z, -Vec3::Z, lo.z),
            (above.z, Vec3::Z, hi.z),
        ] {
            if d < depth {
                (depth, n, face) = (d, nn, f);
            }
        }
        let axis = n.abs();
        Some(Contact { depth, n, at: x * (Vec3::ONE - axis) + axis * face, vs: v3(self.velocity) })
    }

    #[inline(always)]
    fn bound(&self, reach: f32) -> Bound {
        let (lo, hi) = grown(self, reach);
        Bound::Box { lo, hi }
    }
}

/// Box `b`'s corners grown by `reach`.
#[inline(always)]
fn grown(b: &Aabb, reach: f32) -> (Vec3, Vec3) {
    (v3(b.min) - Vec3::splat(reach), v3(b.max) + Vec3::splat(reach))
}

/// The point of the segment `a`–`b` nearest `x` (the WGSL's `capsule_axis_point`).
#[inline(always)]
pub(crate) fn axis_point(a: Vec3, b: Vec3, x: Vec3) -> Vec3 {
    let ab = b - a;
    let len2 = dot3(ab, ab);
    let s = if len2 > 1e-24 { (dot3(x - a, ab) / len2).clamp(0.0, 1.0) } else { 0.0 };
    a + ab * s
}

/// The midpoint of `a`–`b`, `(a + b)·½` (the WGSL's `rod_center`).
#[inline(always)]
pub(crate) fn mid(a: [f32; 4], b: [f32; 4]) -> Vec3 {
    (v3(a) + v3(b)) * 0.5
}

impl Shape for Rod {
    /// By its kind: `capsule_contact`, `cylinder_contact`, `cone_contact`.
    #[inline(always)]
    fn contact(&self, x: Vec3, reach: f32) -> Option<Contact> {
        match self.kind {
            RodKind::Capsule => capsule_contact(self, x, reach),
            RodKind::Cylinder => cylinder_contact(self, x, reach),
            RodKind::Cone => cone_contact(self, x, reach),
        }
    }

    #[inline(always)]
    fn bound(&self, reach: f32) -> Bound {
        let (half, r) = (0.5 * (v3(self.b) - v3(self.a)).length(), self.a[3]);
        let far = match self.kind {
            RodKind::Capsule => half + r + reach,
            // The grown rim: the half length and the radius each grown by `reach`.
            RodKind::Cylinder => ((half + reach).powi(2) + (r + reach).powi(2)).sqrt(),
            // The grown apex lies `reach · slant / r` past the apex, the grown rim `reach`
            // below the base and `reach · (slant + r) / len` out.
            RodKind::Cone => {
                let (len, slant) = (2.0 * half, (r * r + 4.0 * half * half).sqrt());
                let rim = ((half + reach).powi(2) + (r + reach * (slant + r) / len).powi(2)).sqrt();
                rim.max(half + reach * slant / r)
            }
        };
        Bound::Ball { center: mid(self.a, self.b), r: far + 1e-3 }
    }
}

/// A capsule's contact: the points within its radius grown by `reach` of its axis leave
/// along the line from the axis' nearest point.
#[inline(always)]
fn capsule_contact(c: &Rod, x: Vec3, reach: f32) -> Option<Contact> {
    let r = c.a[3] + reach;
    let q = axis_point(v3(c.a), v3(c.b), x);
    let d = x - q;
    let dist2 = dot3(d, d);
    if dist2 >= r * r {
        return None;
    }
    let dist = dist2.sqrt();
    let n = away(d, dist);
    let at = q + n * r;
    let vs = surface_vel(v3(c.velocity), v3(c.spin), at - mid(c.a, c.b));
    Some(Contact { depth: r - dist, n, at, vs })
}

/// A capped cylinder's contact, the cylinder grown by `reach` (radius and half-length
/// each grown by it, edges kept sharp as a box's): leave through the side or the nearer
/// cap, whichever is nearer.
#[inline(always)]
fn cylinder_contact(c: &Rod, x: Vec3, reach: f32) -> Option<Contact> {
    let m = mid(c.a, c.b);
    let ab = v3(c.b) - v3(c.a);
    let len = dot3(ab, ab).sqrt();
    let u = ab / len;
    let d = x - m;
    let t = dot3(d, u);
    let radial = d - u * t;
    let rho2 = dot3(radial, radial);
    let (r, h) = (c.a[3] + reach, len * 0.5 + reach);
    if rho2 >= r * r || t.abs() >= h {
        return None;
    }
    let rho = rho2.sqrt();
    let (side, cap) = (r - rho, h - t.abs());
    let (depth, n, at) = if side < cap {
        let n = if rho > 1e-12 { radial / rho } else { across(u) };
        (side, n, m + u * t + n * r)
    } else {
        let n = if t < 0.0 { -u } else { u };
        (cap, n, x + n * cap)
    };
    Some(Contact { depth, n, at, vs: surface_vel(v3(c.velocity), v3(c.spin), at - m) })
}

/// A cone's contact, the base a disc of its radius `r` about `a`, the apex at `b` (`len`
/// from `a`), grown by `reach` (the base's plane and the slanted side each moved out by
/// it, the rim and the apex kept sharp): leave through the side or the base, whichever is
/// nearer. At height `t` above the base and `ρ` from the axis, the side's outward
/// distance is `(t·r + (ρ − r)·len) / slant`, `slant = √(r² + len²)`.
#[inline(always)]
fn cone_contact(c: &Rod, x: Vec3, reach: f32) -> Option<Contact> {
    let a = v3(c.a);
    let ab = v3(c.b) - a;
    let len = dot3(ab, ab).sqrt();
    let u = ab / len;
    let d = x - a;
    let t = dot3(d, u);
    let radial = d - u * t;
    let rho = dot3(radial, radial).sqrt();
    let r = c.a[3];
    let slant = (r * r + len * len).sqrt();
    let side = reach - (t * r + (rho - r) * len) / slant;
    let base = reach + t;
    if !(side > 0.0 && base > 0.0) {
        return None;
    }
    let (depth, n) = if side < base {
        let out = if rho > 1e-12 { radial / rho } else { across(u) };
        (side, u * (r / slant) + out * (len / slant))
    } else {
        (base, -u)
    };
    let at = x + n * depth;
    Some(Contact { depth, n, at, vs: surface_vel(v3(c.velocity), v3(c.spin), at - mid(c.a, c.b)) })
}

/// A unit direction across the unit axis `u` (a point on a cylinder's axis leaves this
/// way): `x̂` or `ŷ` made perpendicular to `u`. The WGSL's `across`.
#[inline(always)]
fn across(u: Vec3) -> Vec3 {
    let w = if u.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
    let p = w - u * dot3(w, u);
    p / dot3(p, p).sqrt()
}

/// A body (mesh collider) at one substep: its head and every body's values.
#[derive(Debug, Clone, Copy)]
pub struct Body<'a> {
    /// Its pose, velocities and grid.
    pub head: &'a SdfHead,
    /// Every body's values (`head.dims[3]` is its first).
    pub values: &'a [f32],
}

impl Body<'_> {
    /// The field at world `x`: `(φ, n̂)` with `n̂` the world direction of its gradient (up
    /// where it vanishes), or `None` outside its grid or where φ is surely ≥ `reach`. The
    /// WGSL's `body_sample`.
    #[inline(always)]
    pub fn sample(&self, x: Vec3, reach: f32) -> Option<(f32, Vec3)> {
        let hd = self.head;
        let (c0, c1, c2) = (v3(hd.cols[0]), v3(hd.cols[1]), v3(hd.cols[2]));
        let d = x - v3(hd.translation);
        let q = [dot3(c0, d), dot3(c1, d), dot3(c2, d)];
        let [nx, ny, nz, first] = hd.dims;
        let (phi, g) = sample_grid(&hd.lo, [nx, ny, nz], self.values.get(first as usize..)?, q, reach)?;
        let g = Vec3::from(g);
        let gl = dot3(g, g).sqrt();
        let nl = if gl > 1e-12 { g / gl } else { Vec3::Y };
        Some((phi, c0 * nl.x + c1 * nl.y + c2 * nl.z))
    }
}

impl Shape for Body<'_> {
    /// Where the field is below `reach`: pushed along its gradient to `φ = reach`.
    #[inline(always)]
    fn contact(&self, x: Vec3, reach: f32) -> Option<Contact> {
        let (phi, n) = self.sample(x, reach).filter(|&(phi, _)| phi < reach)?;
        let at = x + n * (reach - phi);
        let hd = self.head;
        Some(Contact {
            depth: reach - phi,
            n,
            at,
            vs: surface_vel(v3(hd.velocity), v3(hd.spin), at - v3(hd.translation)),
        })
    }

    /// A ball about the pivot holding the whole grid (generously: a point let through is
    /// only sampled).
    #[inline(always)]
    fn bound(&self, reach: f32) -> Bound {
        let hd = self.head;
        let h = hd.lo[3];
        let far: [f32; 3] = std::array::from_fn(|k| hd.lo[k].abs().max((hd.lo[k] + h * (hd.dims[k] - 1) as f32).abs()));
        let r = (far[0] * far[0] + far[1] * far[1] + far[2] * far[2]).sqrt() * 1.01 + reach + 1e-3;
        Bound::Ball { center: v3(hd.translation), r }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every contact's point lies on the grown surface: pushed there, a point has no
    /// contact left deeper than rounding (1e-5 m), and the depth is the distance moved.
    fn check(shape: &impl Shape, x: Vec3, reach: f32) -> Contact {
        let c = shape.contact(x, reach).expect("inside");
        assert!((c.n.length() - 1.0).abs() < 1e-5, "{c:?}");
        assert!(((c.at - x).length() - c.depth).abs() < 1e-5, "{c:?}");
        if let Some(again) = shape.contact(c.at, reach) {
            assert!(again.depth < 1e-5, "{again:?} after {c:?}");
        }
        c
    }

    #[test]
    fn a_cylinder_pushes_out_through_its_side_or_its_nearer_cap() {
        // Axis along z from −1 to 1, radius 0.5, grown by 0.1: side at ρ = 0.6, caps at
        // |z| = 1.1.
        let c = Rod::new(RodKind::Cylinder, [0.0, 0.0, -1.0], [0.0, 0.0, 1.0], 0.5);
        let side = check(&c, Vec3::new(0.55, 0.0, 0.2), 0.1);
        assert!((side.depth - 0.05).abs() < 1e-6 && side.n == Vec3::X, "{side:?}");
        let cap = check(&c, Vec3::new(0.1, 0.2, -1.05), 0.1);
        assert!((cap.depth - 0.05).abs() < 1e-6 && cap.n == -Vec3::Z, "{cap:?}");
        // On the axis, nearer the side than a cap: out across the axis.
        let axis = check(&c, Vec3::ZERO, 0.1);
        assert!((axis.depth - 0.6).abs() < 1e-6 && axis.n.z.abs() < 1e-6, "{axis:?}");
        // Beyond the rim (outside the grown caps) and off the side: no contact.
        assert_eq!(c.contact(Vec3::new(0.0, 0.0, 1.11), 0.1), None);
        assert_eq!(c.contact(Vec3::new(0.0, 0.61, 0.0), 0.1), None);
        // Turned (axis along x + y), the same point relative to it, the same depth.
        let s = std::f32::consts::FRAC_1_SQRT_2;
        let t = Rod::new(RodKind::Cylinder, [-s, -s, 0.0], [s, s, 0.0], 0.5);
        let turned = check(&t, Vec3::new(0.0, 0.0, 0.55), 0.1);
        assert!((turned.depth - 0.05).abs() < 1e-6 && turned.n == Vec3::Z, "{turned:?}");
    }

    #[test]
    fn a_cone_pushes_out_through_its_side_or_its_base() {
        // Base about the origin, radius 0.5, apex 1 up y: the side's slant √1.25, its
        // outward normal (x̂ + ŷ/2)/√1.25 on the +x side.
        let c = Rod::new(RodKind::Cone, [0.0, 0.0, 0.0], [0.0, 1.0, 0.0], 0.5);
        let slant = 1.25f32.sqrt();
        // Near the side: its distance (t·r + (ρ − r)·len)/slant = (0.1 − 0.2)/slant.
        let side = check(&c, Vec3::new(0.3, 0.2, 0.0), 0.0);
        let n = Vec3::new(1.0, 0.5, 0.0) / slant;
        assert!((side.depth - 0.1 / slant).abs() < 1e-6 && (side.n - n).length() < 1e-6, "{side:?}");
        // On the axis 0.3 up: the base (0.3 away) is nearer than the side (0.35/slant).
        let base = check(&c, Vec3::new(0.0, 0.3, 0.0), 0.0);
        assert!((base.depth - 0.3).abs() < 1e-6 && base.n == -Vec3::Y, "{base:?}");
        // Grown by 0.1: below the base by 0.05 is inside, by 0.11 not; past the apex
        // the grown tip reaches 1 + 0.1·slant/0.5 = 1.224 up the axis.
        let under = check(&c, Vec3::new(0.2, -0.05, 0.1), 0.1);
        assert!((under.depth - 0.05).abs() < 1e-6 && under.n == -Vec3::Y, "{under:?}");
        assert_eq!(c.contact(Vec3::new(0.2, -0.11, 0.1), 0.1), None);
        assert!(c.contact(Vec3::new(0.0, 1.22, 0.0), 0.1).is_some());
        assert_eq!(c.contact(Vec3::new(0.0, 1.23, 0.0), 0.1), None);
        assert_eq!(c.contact(Vec3::new(0.0, 1.01, 0.0), 0.0), None);
        // Outside the side, beside the rim: none.
        assert_eq!(c.contact(Vec3::new(0.51, 0.01, 0.0), 0.0), None);
        // A NaN point touches nothing (the kernels' test is the same).
        assert_eq!(c.contact(Vec3::new(f32::NAN, 0.5, 0.0), 0.1), None);
    }

    #[test]
    fn every_contact_lies_inside_its_shapes_bound() {
        for kind in RodKind::ALL {
            let c = Rod::new(kind, [0.1, 0.2, -1.0], [0.3, 0.0, 1.0], 0.4);
            let (Bound::Ball { center, r }, reach) = (c.bound(0.05), 0.05) else { panic!() };
            let mut hits = 0;
            let mut seed = 12345u64;
            let mut f = || {
                seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                (seed >> 40) as f32 / (1u64 << 24) as f32 * 3.0 - 1.5
            };
            for _ in 0..8192 {
                let x = Vec3::new(f(), f(), f());
                if c.contact(x, reach).is_some() {
                    hits += 1;
                    assert!((x - center).length() < r, "{kind:?}: {x} outside the bound");
                }
            }
            assert!(hits > 100, "{kind:?}: {hits} of 8192 sample points inside: the test would hold nothing");
        }
    }

    #[test]
    fn a_moving_cylinders_surface_moves_with_its_spin() {
        let mut c = Rod::new(RodKind::Cylinder, [0.0, -1.0, 0.0], [0.0, 1.0, 0.0], 0.5);
        c.spin = [0.0, 2.0, 0.0, 0.0];
        c.velocity = [0.0, 0.0, 1.0, 0.0];
        // On the side at +x: spin × arm = (0, 2, 0) × (0.5, y, 0) = (0, 0, −1).
        let hit = c.contact(Vec3::new(0.45, 0.3, 0.0), 0.0).unwrap();
        // The centre's (0, 0, 1) and the spin's (0, 0, −1) cancel exactly (products of 2,
        // 0.5 and 0.3 with zeros: no rounding in z); a contact that left out either
        // would give a speed of 1.
        assert_eq!(hit.vs, Vec3::ZERO, "{hit:?}");
    }
}
