//! An orbit camera: it looks at a target from a distance, turned by yaw and pitch.

use glam::{Mat4, Vec3, Vec4};

/// Orbit camera (right-handed, y up, depth 0..1 as wgpu and Vulkan use it).
#[derive(Debug, Clone, PartialEq)]
pub struct OrbitCamera {
    /// Point looked at, m.
    pub target: Vec3,
    /// Distance from the target, m (kept in `MIN_DISTANCE ..= MAX_DISTANCE`).
    pub distance: f32,
    /// Rotation about +y, radians.
    pub yaw: f32,
    /// Elevation above the xz plane, radians, in (-π/2, π/2).
    pub pitch: f32,
    /// Rotation of the picture about the line of sight, radians (the app's "rotate Z").
    pub roll: f32,
    /// Vertical field of view, radians.
    pub fov_y: f32,
    /// Near plane, m.
    pub near: f32,
    /// Far plane, m.
    pub far: f32,
}

impl OrbitCamera {
    /// Closest zoom.
    pub const MIN_DISTANCE: f32 = 0.2;
    /// Farthest zoom.
    pub const MAX_DISTANCE: f32 = 100.0;
    const PITCH_LIMIT: f32 = 1.55;
}

impl Default for OrbitCamera {
    fn default() -> Self {
        Self {
            target: Vec3::new(0.0, 0.9, 0.0),
            distance: 4.8,
            yaw: 0.6,
            pitch: 0.35,
            roll: 0.0,
            fov_y: 45f32.to_radians(),
            near: 0.05,
            far: 100.0,
        }
    }
}

impl OrbitCamera {
    /// Eye position.
    pub fn eye(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        self.target + self.distance * Vec3::new(cp * sy, sp, cp * cy)
    }

    /// World → view.
    pub fn view(&self) -> Mat4 {
        let eye = self.eye();
        let up = glam::Quat::from_axis_angle((self.target - eye).normalize(), self.roll) * Vec3::Y;
        Mat4::look_at_rh(eye, self.target, up)
    }

    /// View → clip for a target of `aspect` = width / height.
    pub fn proj(&self, aspect: f32) -> Mat4 {
        Mat4::perspective_rh(self.fov_y, aspect.max(1e-3), self.near, self.far)
    }

    /// World → clip.
    pub fn view_proj(&self, aspect: f32) -> Mat4 {
        self.proj(aspect) * self.view()
    }

    /// Turns the camera by `dyaw`, `dpitch` radians (pitch is clamped short of the poles).
    pub fn rotate(&mut self, dyaw: f32, dpitch: f32) {
        self.yaw = (self.yaw + dyaw).rem_euclid(std::f32::consts::TAU);
        self.pitch = (self.pitch + dpitch).clamp(-Self::PITCH_LIMIT, Self::PITCH_LIMIT);
    }

    /// Rolls the picture by `droll` radians about the line of sight.
    pub fn roll_by(&mut self, droll: f32) {
        if droll.is_finite() {
            self.roll = (self.roll + droll).rem_euclid(std::f32::consts::TAU);
        }
    }

    /// Multiplies the distance by `factor` (< 1 zooms in), within the allowed range.
    pub fn zoom(&mut self, factor: f32) {
        if factor.is_finite() && factor > 0.0 {
            self.distance = (self.distance * factor).clamp(Self::MIN_DISTANCE, Self::MAX_DISTANCE);
        }
    }

    /// Pixel coordinates (origin top left) of a world point on a `width × height` target,
    /// or `None` behind the camera.
    pub fn project(&self, p: Vec3, width: u32, height: u32) -> Option<[f32; 2]> {
        let clip = self.view_proj(width as f32 / height.max(1) as f32) * Vec4::new(p.x, p.y, p.z, 1.0);
        if clip.w <= 0.0 {
            return None;
        }
        let ndc = clip / clip.w;
        Some([(ndc.x * 0.5 + 0.5) * width as f32, (0.5 - ndc.y * 0.5) * height as f32])
    }

    /// The world-space ray `(origin, unit direction)` through pixel `(x, y)`.
    pub fn ray(&self, x: f32, y: f32, width: u32, height: u32) -> (Vec3, Vec3) {
        let inv = self.view_proj(width as f32 / height.max(1) as f32).inverse();
        let ndc_x = 2.0 * x / width.max(1) as f32 - 1.0;
        let ndc_y = 1.0 - 2.0 * y / height.max(1) as f32;
        let near = inv.project_point3(Vec3::new(ndc_x, ndc_y, 0.0));
        let far = inv.project_point3(Vec3::new(ndc_x, ndc_y, 1.0));
        (near, (far - near).normalize())
    }

    /// Where the ray through pixel `(x, y)` meets the plane through `point` facing the
    /// camera: the drag target for a grabbed particle at `point`.
    pub fn drag_target(&self, point: Vec3, x: f32, y: f32, width: u32, height: u32) -> Vec3 {
        let (o, d) = self.ray(x, y, width, height);
        let nrm = (self.eye() - self.target).normalize();
        let denom = d.dot(nrm);
        if denom.abs() < 1e-6 {
            return point;
        }
        let t = (point - o).dot(nrm) / denom;
        o + d * t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn project_then_drag_target_round_trips() {
        let cam = OrbitCamera::default();
        let p = Vec3::new(0.3, 1.1, -0.2);
        let [x, y] = cam.project(p, 800, 600).unwrap();
        let back = cam.drag_target(p, x, y, 800, 600);
        // f32 through two 4×4 inversions: a few µm at 5 m.
        assert!((back - p).length() < 1e-4, "{back} vs {p}");
    }

    #[test]
    fn zoom_and_pitch_stay_in_range() {
        let mut cam = OrbitCamera::default();
        cam.zoom(1e-9);
        assert_eq!(cam.distance, OrbitCamera::MIN_DISTANCE);
        cam.zoom(f32::NAN);
        assert_eq!(cam.distance, OrbitCamera::MIN_DISTANCE);
        cam.rotate(0.0, 10.0);
        assert!(cam.pitch < std::f32::consts::FRAC_PI_2);
    }
}
