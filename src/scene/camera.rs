//! Pinhole camera: pixel coordinates (plus a jitter) → primary ray. Pixel (0,0) is the top-left;
//! a pixel's value is the box-filtered average of radiance over its area.

use crate::math::Vec3;

/// A pinhole camera with a vertical field of view.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub position: Vec3,
    /// Forward unit vector.
    pub forward: Vec3,
    /// Right unit vector.
    pub right: Vec3,
    /// Up unit vector (orthogonal to forward).
    pub up: Vec3,
    /// Vertical field of view in degrees (set it through a constructor: rays use the cached
    /// tangent).
    pub fov_deg: f32,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// `tan(fov/2)`, computed once (it was 2% of `pt` on `ring`, per camera ray).
    tan_half: f32,
}

impl Camera {
    /// Builds a camera; `look_at != position` and `up` not parallel to the view are checked by the loader.
    pub fn new(position: Vec3, look_at: Vec3, up: Vec3, fov_deg: f32, width: u32, height: u32) -> Self {
        let forward = (look_at - position).normalize();
        let right = forward.cross(up).normalize();
        let up = right.cross(forward);
        Camera::from_frame(position, (forward, right, up), fov_deg, width, height)
    }

    /// A camera from its orthonormal frame `(forward, right, up)` (checked by the loader).
    pub fn from_frame(
        position: Vec3,
        (forward, right, up): (Vec3, Vec3, Vec3),
        fov_deg: f32,
        width: u32,
        height: u32,
    ) -> Self {
        let tan_half = (fov_deg.to_radians() * 0.5).tan();
        Camera { position, forward, right, up, fov_deg, width, height, tan_half }
    }

    /// The same camera at another resolution (the field of view stays vertical).
    pub fn with_resolution(&self, width: u32, height: u32) -> Self {
        Camera { width, height, ..self.clone() }
    }

    /// `tan(fov/2)`: half the image plane's height at distance 1.
    #[inline]
    pub fn tan_half_fov(&self) -> f32 {
        self.tan_half
    }

    /// Unit direction through film position (px, py) in pixels, (0,0) = top-left corner.
    #[inline]
    pub fn direction(&self, px: f32, py: f32) -> Vec3 {
        let tan_half = self.tan_half;
        let aspect = self.width as f32 / self.height as f32;
        let sx = (2.0 * px / self.width as f32 - 1.0) * tan_half * aspect;
        let sy = (1.0 - 2.0 * py / self.height as f32) * tan_half;
        (self.forward + sx * self.right + sy * self.up).normalize()
    }

    /// Projects a world point to film coordinates (pixels); `None` if behind the camera.
    pub fn project(&self, p: Vec3) -> Option<(f32, f32)> {
        let d = p - self.position;
        let z = d.dot(self.forward);
        if z <= 1e-6 {
            return None;
        }
        let tan_half = self.tan_half;
        let aspect = self.width as f32 / self.height as f32;
        let sx = d.dot(self.right) / z / (tan_half * aspect);
        let sy = d.dot(self.up) / z / tan_half;
        Some(((sx + 1.0) * 0.5 * self.width as f32, (1.0 - sy) * 0.5 * self.height as f32))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn centre_pixel_looks_forward_and_projection_inverts_direction() {
        let c = Camera::new(Vec3::new(0.0, 1.0, 3.88), Vec3::new(0.0, 1.0, 0.0), Vec3::Y, 39.3077, 64, 32);
        assert!((c.direction(32.0, 16.0) - Vec3::new(0.0, 0.0, -1.0)).length() < 1e-5);
        // top-left pixel looks up and left
        let d = c.direction(0.0, 0.0);
        assert!(d.x < 0.0 && d.y > 0.0);
        let (px, py) = c.project(c.position + 2.0 * c.direction(10.5, 7.25)).unwrap();
        assert!((px - 10.5).abs() < 1e-3 && (py - 7.25).abs() < 1e-3);
    }
}
