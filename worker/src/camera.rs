//! The pinhole perspective camera.

use glam::Vec3A;
use restauro_scene::load::ResolvedCamera;

#[derive(Clone, Copy, Debug)]
pub struct Camera {
    pub origin: Vec3A,
    forward: Vec3A,
    right: Vec3A,
    up: Vec3A,
    /// tan(vertical field / 2).
    tan_half: f32,
    pub width: u32,
    pub height: u32,
}

impl Camera {
    pub fn new(c: &ResolvedCamera) -> Self {
        let origin = Vec3A::from(c.position.map(|v| v as f32));
        let forward = (Vec3A::from(c.target.map(|v| v as f32)) - origin).normalize();
        let right = forward.cross(Vec3A::from(c.up.map(|v| v as f32))).normalize();
        let up = right.cross(forward);
        let tan_half = (c.vertical_fov_deg.to_radians() / 2.0).tan() as f32;
        Self { origin, forward, right, up, tan_half, width: c.width, height: c.height }
    }

    /// The unit direction through the image point (px, py) in pixels from the top-left corner.
    #[inline]
    pub fn direction(&self, px: f32, py: f32) -> Vec3A {
        let (w, h) = (self.width as f32, self.height as f32);
        let sx = (2.0 * px / w - 1.0) * self.tan_half * w / h;
        let sy = (1.0 - 2.0 * py / h) * self.tan_half;
        (self.forward + self.right * sx + self.up * sy).normalize()
    }
}
