//! The vocabulary a scene format hands `builder::SceneBuilder`: each value with its provenance
//! (`Origin`: the line and key in the file), and the one error type of scene loading.
//!
//! Invariants: `SceneError::line` 0 means unknown, and is then not printed; a key is printed
//! only when there is one.

use crate::math::{Rgb, Vec2, Vec3};

/// A scene loading error with its location.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneError {
    /// File name.
    pub file: String,
    /// 1-based line (0 when unknown).
    pub line: usize,
    /// The offending key (may be empty).
    pub key: String,
    /// What is wrong.
    pub message: String,
}

impl std::fmt::Display for SceneError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        // line 0 is "unknown": no line rather than a false one
        match self.line {
            0 => write!(f, "{}: ", self.file)?,
            line => write!(f, "{}:{line}: ", self.file)?,
        }
        if !self.key.is_empty() {
            write!(f, "key `{}`: ", self.key)?;
        }
        write!(f, "{}", self.message)
    }
}

impl std::error::Error for SceneError {}

/// Where an element came from in the scene file: its line (1-based, 0 unknown) and key.
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) struct Origin {
    /// Line.
    pub line: usize,
    /// Key (`shape[2].u`, `rectangle.to_world`).
    pub key: String,
}

impl Origin {
    /// An origin.
    pub fn new(line: usize, key: impl Into<String>) -> Origin {
        Origin { line, key: key.into() }
    }
}

/// How the camera looks: at a target with an up vector (TOML, a lone Mitsuba `lookat`), or along
/// a frame taken from a matrix (forward, up, right).
pub(super) enum View {
    /// Target point and up vector.
    LookAt { target: Vec3, up: Vec3 },
    /// The columns of a camera matrix.
    Frame { forward: Vec3, up: Vec3, right: Vec3 },
}

/// A camera as a format gives it, with the origin of each of its values.
pub(super) struct CameraSpec {
    /// Eye position.
    pub position: (Vec3, Origin),
    /// View; its origin names the target (or the matrix).
    pub view: (View, Origin),
    /// Origin of the up vector.
    pub up_at: Origin,
    /// Vertical field of view, degrees.
    pub fov: (f32, Origin),
    /// Width, height.
    pub resolution: ([u32; 2], Origin),
}

/// One shape's common part: where it is, its material and emission, what it is (for messages).
pub(super) struct ShapeIn {
    /// The shape's origin (its line; the key prefix of the format, `shape[2]` or `shape.ply`).
    pub at: Origin,
    /// Material index (0 for emitters).
    pub material: u32,
    /// Area-light radiance (from `SceneBuilder::emission`) and its origin.
    pub emission: Option<(Rgb, Origin)>,
    /// Words after "in" in warnings (`ring.ply`, `shape `rectangle``).
    pub what: String,
    /// Keep shading normals of unit length to 1e-5 bit-exact (Mitsuba's exported meshes).
    pub exact_normals: bool,
}

/// What a triangle's corners carry beside their positions.
#[derive(Clone, Copy, Debug, Default)]
pub struct Corners {
    /// Shading normals (smooth meshes).
    pub n: Option<[Vec3; 3]>,
    /// Texture coordinates.
    pub uv: Option<[Vec2; 3]>,
}
