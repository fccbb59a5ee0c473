//! Pinhole camera: pixel coordinates (plus a jitter) → primary ray. Pixel (0,0) is the top-left;
//! a pixel's value is the box-filtered average of radiance over its area.
//!
//! A crop window (Mitsuba's `crop_offset_*`, `crop_width/height`): the projection is the full
//! film's (`film`, its aspect and field of view), the image is the window (`width` × `height` at
//! `offset` in the film's pixels), so a cropped image's pixel (x, y) is the full image's pixel
//! (x + offset.x, y + offset.y), ray for ray.
//!
//! Invariants: without a window `film` = (`width`, `height`) and `offset` = 0, and every ray and
//! projection is computed with the same operations as before windows existed.

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
    /// The full film's size in pixels (the projection's; (`width`, `height`) without a window).
    pub film: [f32; 2],
    /// The image's top-left corner in the full film's pixels (0 without a window).
    pub offset: [f32; 2],
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
        let (film, offset) = ([width as f32, height as f32], [0.0; 2]);
        Camera { position, forward, right, up, fov_deg, width, height, film, offset, tan_half }
    }

    /// The window `size` at `offset` of this camera's film as the image (the caller checks that
    /// it lies inside the film).
    pub fn with_crop(&self, offset: [u32; 2], size: [u32; 2]) -> Self {
        let offset = [offset[0] as f32, offset[1] as f32];
        Camera { width: size[0], height: size[1], offset, ..self.clone() }
    }

    /// The same camera at another resolution (the field of view stays vertical); a crop window
    /// scales with the image, so that it shows the same part of the view.
    pub fn with_resolution(&self, width: u32, height: u32) -> Self {
        if !self.is_cropped() {
            return Camera { width, height, film: [width as f32, height as f32], ..self.clone() };
        }
        let s = [width as f32 / self.width as f32, height as f32 / self.height as f32];
        let film = [self.film[0] * s[0], self.film[1] * s[1]];
        let offset = [self.offset[0] * s[0], self.offset[1] * s[1]];
        Camera { width, height, film, offset, ..self.clone() }
    }

    /// Whether the image is a window of a larger film.
    pub fn is_cropped(&self) -> bool {
        self.offset != [0.0; 2] || self.film != [self.width as f32, self.height as f32]
    }

    /// A pixel's side on the image plane at distance 1 (the full film's pixel).
    #[inline]
    pub fn pixel_side(&self) -> f32 {
        2.0 * self.tan_half / self.film[1]
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
        let [fw, fh] = self.film;
        let (px, py) = (px + self.offset[0], py + self.offset[1]);
        let aspect = fw / fh;
        let sx = (2.0 * px / fw - 1.0) * tan_half * aspect;
        let sy = (1.0 - 2.0 * py / fh) * tan_half;
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
        let [fw, fh] = self.film;
        let aspect = fw / fh;
        let sx = d.dot(self.right) / z / (tan_half * aspect);
        let sy = d.dot(self.up) / z / tan_half;
        Some(((sx + 1.0) * 0.5 * fw - self.offset[0], (1.0 - sy) * 0.5 * fh - self.offset[1]))
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

    /// A window's pixel (x, y) is the full film's (x + ox, y + oy), bit for bit; projection
    /// returns window coordinates; `with_resolution` keeps the window's part of the view.
    #[test]
    fn crop_window_is_the_full_films_pixels() {
        let full = Camera::new(Vec3::new(0.3, 1.0, 3.88), Vec3::new(0.0, 1.0, 0.0), Vec3::Y, 39.3, 40, 30);
        let crop = full.with_crop([19, 13], [16, 12]);
        assert!((crop.width, crop.height, crop.is_cropped(), full.is_cropped()) == (16, 12, true, false));
        for (x, y) in [(0.0, 0.0), (0.5, 0.5), (15.99, 11.99), (7.25, 3.5)] {
            assert_eq!(crop.direction(x, y), full.direction(x + 19.0, y + 13.0), "({x}, {y})");
        }
        let (px, py) = crop.project(crop.position + 3.0 * crop.direction(4.5, 2.25)).unwrap();
        assert!((px - 4.5).abs() < 1e-3 && (py - 2.25).abs() < 1e-3, "{px} {py}");
        assert_eq!(crop.pixel_side(), full.pixel_side());
        let twice = crop.with_resolution(32, 24);
        assert!((twice.direction(9.0, 5.0) - crop.direction(4.5, 2.5)).length() < 1e-6);
        // without a window, another resolution is the plain camera at that resolution
        assert_eq!(
            full.with_resolution(20, 10),
            Camera::new(full.position, Vec3::new(0.0, 1.0, 0.0), Vec3::Y, 39.3, 20, 10)
        );
    }
}
