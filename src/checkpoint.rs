//! Render checkpoints: the summed film plus enough metadata to resume a progressive render
//! and to refuse resuming a different render.
//!
//! File layout (all integers little-endian):
//!
//! | offset | size | content                                              |
//! |--------|------|------------------------------------------------------|
//! | 0      | 8    | magic `b"FCSTCKPT"`                                  |
//! | 8      | 4    | format version ([`FORMAT_VERSION`])                  |
//! | 12     | 4    | reserved, 0                                          |
//! | 16     | 8    | payload length in bytes                              |
//! | 24     | 8    | checksum of the payload (64-bit word-wise mix hash)  |
//! | 32     | n    | payload: [`Checkpoint`] encoded with `bitcode` 0.6   |
//!
//! Invariants:
//! * The film holds the sums of passes `0..passes_done`; `next_pass >= passes_done`.
//! * [`Checkpoint::save`] is atomic: it writes `<path>.tmp`, fsyncs it, renames it over
//!   `<path>` and fsyncs the directory, so a crash leaves either the old or the new file.
//! * [`Checkpoint::load`] never panics on a bad file: wrong magic, other version, short or
//!   long file, checksum mismatch and undecodable payload are distinct errors naming the file.
//! * [`Checkpoint::validate`] refuses a resume whose scene hash, seed, method, resolution or any
//!   [`Checkpoint::job`] key (`-D` values, method options such as `max_depth`) differs, naming
//!   every differing key with both values.
//! * bitcode's format is only stable within a bitcode major version: bump
//!   [`FORMAT_VERSION`] whenever the struct or the bitcode major version changes.

use std::fmt;
use std::fs::{self, File};
use std::io::{self, Write};
use std::path::{Path, PathBuf};

/// First 8 bytes of every checkpoint file.
pub const MAGIC: [u8; 8] = *b"FCSTCKPT";
/// Version of the file layout and of the encoded struct.
pub const FORMAT_VERSION: u32 = 2;
/// Header length in bytes.
pub const HEADER_LEN: usize = 32;

/// Resumable state of a progressive render.
#[derive(Debug, Clone, PartialEq, bitcode::Encode, bitcode::Decode)]
pub struct Checkpoint {
    /// Hash of the scene description the film belongs to.
    pub scene_hash: u64,
    /// Master random seed.
    pub seed: u64,
    /// Rendering method name (e.g. "pt", "iws", "iws+cf").
    pub method: String,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Passes `0..passes_done` are summed into `film`.
    pub passes_done: u64,
    /// Next pass index to render.
    pub next_pass: u64,
    /// Film sums (layout owned by the film module; opaque here).
    pub film: Vec<f64>,
    /// Samples per pixel accumulated so far.
    pub spp: u64,
    /// Render time accumulated so far, in seconds.
    pub elapsed_secs: f64,
    /// Every other input that changes the image, as (key, value) pairs compared on resume: the
    /// `-D NAME` values and each method option (`option KEY`, its serialized value; the
    /// pipeline decides which, see `pipeline::checkpoints::job_keys`).
    pub job: Vec<(String, String)>,
}

/// Why a checkpoint could not be saved or loaded. Every variant names the file.
#[derive(Debug)]
pub enum CheckpointError {
    /// Reading, writing, syncing or renaming failed.
    Io {
        /// File concerned.
        path: PathBuf,
        /// What was being done.
        action: &'static str,
        /// Underlying error.
        source: io::Error,
    },
    /// The file does not start with [`MAGIC`].
    BadMagic {
        /// File concerned.
        path: PathBuf,
    },
    /// The file has another format version.
    Version {
        /// File concerned.
        path: PathBuf,
        /// Version in the file.
        found: u32,
        /// Version this program reads.
        expected: u32,
    },
    /// The file is shorter than its header says (or than the header itself).
    Truncated {
        /// File concerned.
        path: PathBuf,
        /// Bytes expected.
        expected: u64,
        /// Bytes present.
        found: u64,
    },
    /// The file is longer than its header says.
    TrailingBytes {
        /// File concerned.
        path: PathBuf,
        /// Bytes expected.
        expected: u64,
        /// Bytes present.
        found: u64,
    },
    /// The payload checksum does not match (the file is corrupted).
    Checksum {
        /// File concerned.
        path: PathBuf,
    },
    /// The payload could not be decoded or is inconsistent.
    Decode {
        /// File concerned.
        path: PathBuf,
        /// Decoder message.
        message: String,
    },
}

impl fmt::Display for CheckpointError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use CheckpointError::*;
        match self {
            Io { path, action, source } => write!(f, "checkpoint {}: {action} failed: {source}", path.display()),
            BadMagic { path } => write!(f, "checkpoint {}: not a forecast checkpoint (bad magic)", path.display()),
            Version { path, found, expected } => write!(
                f,
                "checkpoint {}: format version {found}, this program reads version {expected}",
                path.display()
            ),
            Truncated { path, expected, found } => {
                write!(f, "checkpoint {}: truncated ({found} bytes, expected {expected})", path.display())
            }
            TrailingBytes { path, expected, found } => {
                write!(f, "checkpoint {}: {found} bytes, expected {expected} (trailing data)", path.display())
            }
            Checksum { path } => write!(f, "checkpoint {}: checksum mismatch (file corrupted)", path.display()),
            Decode { path, message } => {
                write!(f, "checkpoint {}: cannot decode: {message}", path.display())
            }
        }
    }
}

impl std::error::Error for CheckpointError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            CheckpointError::Io { source, .. } => Some(source),
            _ => None,
        }
    }
}

/// Why a checkpoint does not belong to the requested render ([`Checkpoint::validate`]).
#[derive(Clone, Debug, PartialEq)]
pub struct ResumeMismatch {
    /// Every difference in words, in the order checked: the job keys, then the scene hash, the
    /// seed, the method, the resolution and the checkpoint's own consistency (`seed differs
    /// (checkpoint 42, requested 43)`).
    pub reasons: Vec<String>,
}

impl fmt::Display for ResumeMismatch {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "cannot resume from this checkpoint: {}", self.reasons.join("; "))
    }
}

impl std::error::Error for ResumeMismatch {}

/// Every key whose value differs between the checkpoint's `old` pairs and the requested `new`
/// ones (a key on one side only counts, shown as `unset`), in key order.
fn job_mismatches(old: &[(String, String)], new: &[(String, String)]) -> Vec<String> {
    let map = |v: &[(String, String)]| v.iter().cloned().collect::<std::collections::BTreeMap<_, _>>();
    let (old, new) = (map(old), map(new));
    let keys: std::collections::BTreeSet<&String> = old.keys().chain(new.keys()).collect();
    let show = |v: Option<&String>| v.map_or("unset".to_string(), |s| s.clone());
    keys.into_iter()
        .filter(|k| old.get(*k) != new.get(*k))
        .map(|k| format!("{k} differs (checkpoint {}, requested {})", show(old.get(k)), show(new.get(k))))
        .collect()
}

/// 64-bit checksum of `bytes`: 8-byte words mixed with a multiply-rotate, then a final
/// avalanche. Not cryptographic; detects corruption and truncation of the payload.
pub fn checksum(bytes: &[u8]) -> u64 {
    const K: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut h: u64 = 0x243F_6A88_85A3_08D3 ^ (bytes.len() as u64).wrapping_mul(K);
    let mut words = bytes.chunks_exact(8);
    for w in &mut words {
        let mut a = [0u8; 8];
        a.copy_from_slice(w);
        h = (h ^ u64::from_le_bytes(a)).wrapping_mul(K).rotate_left(29);
    }
    let rest = words.remainder();
    if !rest.is_empty() {
        let mut a = [0u8; 8];
        a[..rest.len()].copy_from_slice(rest);
        h = (h ^ u64::from_le_bytes(a)).wrapping_mul(K).rotate_left(29);
    }
    h ^= h >> 33;
    h = h.wrapping_mul(0xFF51_AFD7_ED55_8CCD);
    h ^= h >> 33;
    h = h.wrapping_mul(0xC4CE_B9FE_1A85_EC53);
    h ^ (h >> 33)
}

/// `<path>.tmp`, the temporary file [`Checkpoint::save`] writes first.
pub fn tmp_path(path: &Path) -> PathBuf {
    let mut s = path.as_os_str().to_os_string();
    s.push(".tmp");
    PathBuf::from(s)
}

fn io_err<'a>(path: &'a Path, action: &'static str) -> impl FnOnce(io::Error) -> CheckpointError + 'a {
    move |source| CheckpointError::Io { path: path.to_path_buf(), action, source }
}

impl Checkpoint {
    /// Encodes the checkpoint into the file format described in the module docs.
    pub fn to_bytes(&self) -> Vec<u8> {
        let payload = bitcode::encode(self);
        let mut out = Vec::with_capacity(HEADER_LEN + payload.len());
        out.extend_from_slice(&MAGIC);
        out.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
        out.extend_from_slice(&0u32.to_le_bytes());
        out.extend_from_slice(&(payload.len() as u64).to_le_bytes());
        out.extend_from_slice(&checksum(&payload).to_le_bytes());
        out.extend_from_slice(&payload);
        out
    }

    /// Decodes a checkpoint from file bytes; `path` is only used in error messages.
    pub fn from_bytes(bytes: &[u8], path: &Path) -> Result<Checkpoint, CheckpointError> {
        let p = || path.to_path_buf();
        let found = bytes.len() as u64;
        if bytes.len() < MAGIC.len() || bytes[..MAGIC.len()] != MAGIC {
            // A short file that is a prefix of the magic is a truncated checkpoint.
            if bytes.len() < MAGIC.len() && !bytes.is_empty() && MAGIC.starts_with(bytes) {
                return Err(CheckpointError::Truncated { path: p(), expected: HEADER_LEN as u64, found });
            }
            if bytes.is_empty() {
                return Err(CheckpointError::Truncated { path: p(), expected: HEADER_LEN as u64, found });
            }
            return Err(CheckpointError::BadMagic { path: p() });
        }
        if bytes.len() < HEADER_LEN {
            return Err(CheckpointError::Truncated { path: p(), expected: HEADER_LEN as u64, found });
        }
        let u32_at = |o: usize| u32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]);
        let u64_at = |o: usize| {
            let mut a = [0u8; 8];
            a.copy_from_slice(&bytes[o..o + 8]);
            u64::from_le_bytes(a)
        };
        let version = u32_at(8);
        if version != FORMAT_VERSION {
            return Err(CheckpointError::Version { path: p(), found: version, expected: FORMAT_VERSION });
        }
        let payload_len = u64_at(16);
        let expected = (HEADER_LEN as u64).saturating_add(payload_len);
        if found < expected {
            return Err(CheckpointError::Truncated { path: p(), expected, found });
        }
        if found > expected {
            return Err(CheckpointError::TrailingBytes { path: p(), expected, found });
        }
        let payload = &bytes[HEADER_LEN..];
        if checksum(payload) != u64_at(24) {
            return Err(CheckpointError::Checksum { path: p() });
        }
        let ck: Checkpoint =
            bitcode::decode(payload).map_err(|e| CheckpointError::Decode { path: p(), message: e.to_string() })?;
        ck.check_consistency().map_err(|message| CheckpointError::Decode { path: p(), message })?;
        Ok(ck)
    }

    /// Internal consistency that holds for every checkpoint this program writes.
    fn check_consistency(&self) -> Result<(), String> {
        if self.next_pass < self.passes_done {
            return Err(format!("next_pass {} < passes_done {}", self.next_pass, self.passes_done));
        }
        if !(self.elapsed_secs.is_finite() && self.elapsed_secs >= 0.0) {
            return Err(format!("elapsed_secs is {}", self.elapsed_secs));
        }
        let pixels = self.width as u64 * self.height as u64;
        if pixels > 0 && !(self.film.len() as u64).is_multiple_of(pixels) {
            return Err(format!(
                "film has {} values, not a multiple of {}x{} pixels",
                self.film.len(),
                self.width,
                self.height
            ));
        }
        Ok(())
    }

    /// Writes the checkpoint atomically: `<path>.tmp`, fsync, rename over `path`, then a
    /// best-effort fsync of the directory. On error the temporary file is removed.
    pub fn save(&self, path: &Path) -> Result<(), CheckpointError> {
        let tmp = tmp_path(path);
        let result = self.write_tmp_and_rename(path, &tmp);
        if result.is_err() {
            let _ = fs::remove_file(&tmp);
        }
        result
    }

    fn write_tmp_and_rename(&self, path: &Path, tmp: &Path) -> Result<(), CheckpointError> {
        let bytes = self.to_bytes();
        let mut f = File::create(tmp).map_err(io_err(tmp, "create"))?;
        f.write_all(&bytes).map_err(io_err(tmp, "write"))?;
        f.sync_all().map_err(io_err(tmp, "fsync"))?;
        drop(f);
        fs::rename(tmp, path).map_err(io_err(path, "rename temporary file onto"))?;
        // Persist the rename itself; not every platform/filesystem allows syncing a directory.
        let dir = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        if let Ok(d) = File::open(dir) {
            let _ = d.sync_all();
        }
        Ok(())
    }

    /// Reads and checks a checkpoint file (see [`CheckpointError`] for the failure cases).
    pub fn load(path: &Path) -> Result<Checkpoint, CheckpointError> {
        let bytes = crate::atomic_io::read_regular(path).map_err(io_err(path, "read"))?;
        Self::from_bytes(&bytes, path)
    }

    /// Checks that this checkpoint belongs to the render described by the arguments (`job`: the
    /// [`Checkpoint::job`] pairs of the requested render); the error lists every mismatch in words.
    pub fn validate(
        &self,
        scene_hash: u64,
        seed: u64,
        method: &str,
        (width, height): (u32, u32),
        job: &[(String, String)],
    ) -> Result<(), ResumeMismatch> {
        let mut why = Vec::new();
        if self.method != method {
            why.push(format!("method differs (checkpoint {:?}, requested {method:?})", self.method));
        }
        // another method has other options: only the `-D` values are worth comparing then
        let other_method = self.method != method;
        why.extend(job_mismatches(&self.job, job).into_iter().filter(|w| !(other_method && w.starts_with("option "))));
        if self.scene_hash != scene_hash {
            why.push(format!(
                "scene changed (checkpoint scene hash {:016x}, current {:016x})",
                self.scene_hash, scene_hash
            ));
        }
        if self.seed != seed {
            why.push(format!("seed differs (checkpoint {}, requested {seed})", self.seed));
        }
        if (self.width, self.height) != (width, height) {
            why.push(format!(
                "resolution differs (checkpoint {}x{}, requested {width}x{height})",
                self.width, self.height
            ));
        }
        if let Err(e) = self.check_consistency() {
            why.push(format!("checkpoint is inconsistent: {e}"));
        }
        if why.is_empty() {
            Ok(())
        } else {
            Err(ResumeMismatch { reasons: why })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Checkpoint {
        Checkpoint {
            scene_hash: 0xDEAD_BEEF_0123_4567,
            seed: 42,
            method: "iws+cf".into(),
            width: 4,
            height: 3,
            passes_done: 17,
            next_pass: 17,
            film: (0..4 * 3 * 7)
                .map(|i| match i {
                    0 => f64::MAX,
                    1 => -0.0,
                    2 => 1e-300,
                    _ => i as f64 * 0.37 - 3.0,
                })
                .collect(),
            spp: 17 * 4,
            elapsed_secs: 12.5,
            job: vec![("-D spp".into(), "4".into()), ("option max_depth".into(), "8".into())],
        }
    }

    fn scratch_dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("forecast-ckpt-test-{}-{name}", std::process::id()));
        let _ = fs::remove_dir_all(&d);
        fs::create_dir_all(&d).expect("create test dir");
        d
    }

    #[test]
    fn round_trip_in_memory_and_on_disk() {
        let c = sample();
        let bytes = c.to_bytes();
        assert_eq!(&bytes[..8], b"FCSTCKPT");
        assert_eq!(Checkpoint::from_bytes(&bytes, Path::new("mem")).expect("decode"), c);

        let dir = scratch_dir("rt");
        let path = dir.join("render.ckpt");
        c.save(&path).expect("save");
        let back = Checkpoint::load(&path).expect("load");
        assert_eq!(back, c);
        assert_eq!(
            back.film.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
            c.film.iter().map(|x| x.to_bits()).collect::<Vec<_>>()
        );
        assert!(!tmp_path(&path).exists(), "temporary file left behind");
        // Overwrite with a newer state: still no .tmp, new content visible.
        let mut c2 = c.clone();
        c2.passes_done = 20;
        c2.next_pass = 20;
        c2.save(&path).expect("save again");
        assert_eq!(Checkpoint::load(&path).expect("load again"), c2);
        assert!(!tmp_path(&path).exists());
        let names: Vec<_> = fs::read_dir(&dir).expect("ls").filter_map(|e| e.ok()).map(|e| e.file_name()).collect();
        assert_eq!(names, vec![std::ffi::OsString::from("render.ckpt")]);
        let _ = fs::remove_dir_all(&dir);
    }

    #[test]
    fn save_into_missing_directory_is_an_error_naming_the_file() {
        let path = std::env::temp_dir().join("forecast-no-such-dir-xyz/sub/render.ckpt");
        let e = sample().save(&path).expect_err("must fail");
        let msg = e.to_string();
        assert!(msg.contains("render.ckpt.tmp") && msg.contains("create"), "{msg}");
    }

    #[test]
    fn load_missing_file_names_it() {
        let e = Checkpoint::load(Path::new("/nonexistent/x.ckpt")).expect_err("must fail");
        assert!(matches!(e, CheckpointError::Io { .. }));
        assert!(e.to_string().contains("/nonexistent/x.ckpt"));
    }

    #[test]
    fn corrupted_files_give_specific_errors() {
        let good = sample().to_bytes();
        let p = Path::new("bad.ckpt");
        let err = |b: &[u8]| Checkpoint::from_bytes(b, p).expect_err("must fail");

        let mut b = good.clone();
        b[0] = b'X';
        assert!(matches!(err(&b), CheckpointError::BadMagic { .. }));
        assert!(matches!(err(b"hello world, this is not a checkpoint at all"), CheckpointError::BadMagic { .. }));

        let mut b = good.clone();
        b[8..12].copy_from_slice(&99u32.to_le_bytes());
        assert!(matches!(err(&b), CheckpointError::Version { found: 99, expected: FORMAT_VERSION, .. }));

        for cut in [0, 3, 8, 20, HEADER_LEN, good.len() / 2, good.len() - 1] {
            assert!(matches!(err(&good[..cut]), CheckpointError::Truncated { .. }), "cut at {cut}");
        }

        let mut b = good.clone();
        b.push(0);
        assert!(matches!(err(&b), CheckpointError::TrailingBytes { .. }));

        let mut b = good.clone();
        let mid = HEADER_LEN + (good.len() - HEADER_LEN) / 2;
        b[mid] ^= 0x10;
        let e = err(&b);
        assert!(matches!(e, CheckpointError::Checksum { .. }));
        assert!(e.to_string().contains("bad.ckpt"), "{e}");

        // Header claims an absurd payload length: truncated, no huge allocation.
        let mut b = good.clone();
        b[16..24].copy_from_slice(&u64::MAX.to_le_bytes());
        assert!(matches!(err(&b), CheckpointError::Truncated { .. }));
    }

    #[test]
    fn garbage_payload_with_valid_checksum_is_a_decode_error() {
        let payload = vec![0xFFu8; 64];
        let mut b = Vec::new();
        b.extend_from_slice(&MAGIC);
        b.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
        b.extend_from_slice(&0u32.to_le_bytes());
        b.extend_from_slice(&(payload.len() as u64).to_le_bytes());
        b.extend_from_slice(&checksum(&payload).to_le_bytes());
        b.extend_from_slice(&payload);
        let e = Checkpoint::from_bytes(&b, Path::new("g.ckpt")).expect_err("must fail");
        assert!(matches!(e, CheckpointError::Decode { .. }), "{e}");
    }

    #[test]
    fn corrupted_file_on_disk() {
        let dir = scratch_dir("corrupt");
        let path = dir.join("c.ckpt");
        sample().save(&path).expect("save");
        let mut b = fs::read(&path).expect("read");
        let n = b.len();
        b[n - 3] ^= 0xFF;
        fs::write(&path, &b).expect("write");
        let e = Checkpoint::load(&path).expect_err("must fail");
        assert!(matches!(e, CheckpointError::Checksum { .. }));
        assert!(e.to_string().contains("c.ckpt"));
        fs::write(&path, &b[..n / 2]).expect("write");
        assert!(matches!(Checkpoint::load(&path), Err(CheckpointError::Truncated { .. })));
        let _ = fs::remove_dir_all(&dir);
    }

    #[test]
    fn validate_explains_mismatches() {
        let c = sample();
        assert_eq!(c.validate(c.scene_hash, 42, "iws+cf", (4, 3), &c.job), Ok(()));
        let e = c.validate(1, 43, "pt", (8, 3), &c.job).expect_err("must fail");
        assert_eq!(e.reasons.len(), 4, "{e}");
        let e = e.to_string();
        assert!(e.starts_with("cannot resume from this checkpoint: method differs (checkpoint \"iws+cf\""), "{e}");
        for part in ["scene changed", "seed differs", "method differs", "resolution differs", "4x3", "8x3"] {
            assert!(e.contains(part), "{e}");
        }
        let mut bad = c.clone();
        bad.next_pass = 3;
        let e = bad.validate(c.scene_hash, 42, "iws+cf", (4, 3), &c.job).expect_err("must fail").to_string();
        assert!(e.contains("next_pass"), "{e}");
        let mut bad = c.clone();
        bad.film.pop();
        assert!(bad.validate(c.scene_hash, 42, "iws+cf", (4, 3), &c.job).is_err());
        assert!(Checkpoint::from_bytes(&bad.to_bytes(), Path::new("x")).is_err());
        // another -D value, another max_depth, a -D given on one side only: each key named
        let other = vec![("-D spp".to_string(), "8".to_string()), ("option max_depth".into(), "3".into())];
        let e = c.validate(c.scene_hash, 42, "iws+cf", (4, 3), &other).expect_err("must fail").to_string();
        assert!(e.contains("-D spp differs (checkpoint 4, requested 8)"), "{e}");
        assert!(e.contains("option max_depth differs (checkpoint 8, requested 3)"), "{e}");
        let e = c.validate(c.scene_hash, 42, "iws+cf", (4, 3), &other[1..]).expect_err("must fail").to_string();
        assert!(e.contains("-D spp differs (checkpoint 4, requested unset)"), "{e}");
        // another method: its options are not listed (they are another method's), -D values are
        let e = c.validate(c.scene_hash, 42, "pt", (4, 3), &other).expect_err("must fail");
        assert_eq!(e.reasons.len(), 2, "{e}");
        assert!(e.reasons[0].starts_with("method differs") && e.reasons[1].starts_with("-D spp differs"), "{e}");
    }

    #[test]
    fn checksum_sensitive_to_length_and_content() {
        assert_ne!(checksum(b""), checksum(b"\0"));
        assert_ne!(checksum(b"abcdefgh"), checksum(b"abcdefgi"));
        assert_ne!(checksum(&[0u8; 16]), checksum(&[0u8; 17]));
    }
}
