//! `forecast forecast-map`: the caustic points and their clusters seen from the camera, like
//! BAJ08 Figs. 1 and 2. Each visible caustic point is splatted as a 3×3 dot coloured by its
//! cluster's rank (rank 0 red, then orange, yellow, green, cyan, blue, violet, …); culled
//! clusters are grey. The background is a dim eye-light view of the scene.
//!
//! Invariants: a point is drawn only if the camera sees it (no occluder before it), so the
//! picture shows what the render's shading points will find.

use super::estimator::CausticForecast;
use crate::accel::World;
use crate::image_io::{self, Image};
use crate::scene::Camera;

/// Colour of a rank (kept clusters) or grey for culled ones.
pub fn rank_colour(rank: u32, max_rank: u32) -> [f32; 3] {
    const PALETTE: [[f32; 3]; 8] = [
        [1.0, 0.1, 0.1],
        [1.0, 0.55, 0.0],
        [1.0, 0.95, 0.1],
        [0.2, 0.9, 0.2],
        [0.1, 0.9, 0.9],
        [0.2, 0.4, 1.0],
        [0.7, 0.3, 1.0],
        [1.0, 0.4, 0.8],
    ];
    if rank > max_rank {
        [0.45, 0.45, 0.45]
    } else {
        PALETTE[(rank as usize) % PALETTE.len()]
    }
}

/// Renders the forecast map image at the camera's resolution.
pub fn render_view(world: &World, camera: &Camera, cf: &CausticForecast) -> Image {
    let (w, h) = (camera.width as usize, camera.height as usize);
    let mut img = Image::from_fn(w, h, |x, y| {
        let d = camera.direction(x as f32 + 0.5, y as f32 + 0.5);
        match world.intersect(camera.position, d, f32::INFINITY) {
            Some(hit) => {
                let g = 0.08 + 0.17 * hit.ns.dot(-d).abs();
                [g, g, g]
            }
            None => [0.0; 3],
        }
    });
    let max_rank = cf.opts.max_rank;
    for (i, p) in cf.points.iter().enumerate() {
        let label = cf.clustering.labels.get(i).copied().unwrap_or(u32::MAX);
        let Some(c) = cf.clustering.clusters.get(label as usize) else { continue };
        let pos = p.pos();
        let Some((px, py)) = camera.project(pos) else { continue };
        if px < 0.0 || py < 0.0 || px >= w as f32 || py >= h as f32 {
            continue;
        }
        let to = pos - camera.position;
        let dist = to.length();
        let dir = to / dist;
        if let Some(hit) = world.intersect(camera.position, dir, f32::INFINITY) {
            if hit.t < dist * (1.0 - 1e-3) - 1e-4 {
                continue; // hidden
            }
        }
        let col = rank_colour(c.rank, max_rank);
        for dy in -1i32..=1 {
            for dx in -1i32..=1 {
                img.set((px as i32 + dx).max(0) as usize, (py as i32 + dy).max(0) as usize, col);
            }
        }
    }
    img
}

/// Writes PREFIX.png (the view).
pub fn write_view(prefix: &std::path::Path, img: &Image) -> Result<(), String> {
    let mut s = prefix.as_os_str().to_owned();
    s.push(".png");
    Ok(image_io::write_png_srgb(std::path::Path::new(&s), img, 0.0)?)
}
