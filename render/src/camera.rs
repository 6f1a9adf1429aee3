//! The pinhole perspective camera.

use glam::Vec3A;
use restauro_scene::load::ResolvedCamera;

#[derive(Clone, Copy, Debug)]
pub struct Camera {
    pub origin: Vec3A,
    forward: Vec3A,
    right: Vec3A,
    up: Vec3A,
    /// The image plane at unit distance, as linear maps of the pixel position:
    /// s_x = px·x_per_px − x_half, s_y = y_half − py·y_per_px (tan(fov/2) scaled by the aspect
    /// ratio), computed once so a camera ray costs no division.
    x_per_px: f32,
    x_half: f32,
    y_per_px: f32,
    y_half: f32,
    pub width: u32,
    pub height: u32,
}

impl Camera {
    pub fn new(c: &ResolvedCamera) -> Self {
        let p = &c.pose;
        let origin = Vec3A::from(p.position.map(|v| v as f32));
        let forward = (Vec3A::from(p.target.map(|v| v as f32)) - origin).normalize();
        let right = forward.cross(Vec3A::from(p.up.map(|v| v as f32))).normalize();
        let up = right.cross(forward);
        let tan_half = (p.vertical_fov_deg.to_radians() / 2.0).tan() as f32;
        let (w, h) = (c.width as f32, c.height as f32);
        let x_half = tan_half * w / h;
        Self {
            origin,
            forward,
            right,
            up,
            x_per_px: 2.0 * x_half / w,
            x_half,
            y_per_px: 2.0 * tan_half / h,
            y_half: tan_half,
            width: c.width,
            height: c.height,
        }
    }

    /// The angle (rad) one pixel subtends at the image's centre: a pixel's ray cone widens by
    /// this much per metre travelled (texture filtering, [`crate::texture`]).
    pub fn pixel_spread(&self) -> f32 {
        self.y_per_px
    }

    /// The unit direction through the image point (px, py) in pixels from the top-left corner.
    #[inline]
    pub fn direction(&self, px: f32, py: f32) -> Vec3A {
        let sx = px * self.x_per_px - self.x_half;
        let sy = self.y_half - py * self.y_per_px;
        (self.forward + self.right * sx + self.up * sy).normalize()
    }
}
