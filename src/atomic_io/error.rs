//! `AtomicIoError`: why an output was refused before anything was written (the output guard,
//! [`super::OutputSet`], and [`super::check_output_prefix`]), or why a write of one file or a set
//! failed ([`super::write_set_with`]). `Display` is the message users see.

use std::io;
use std::path::{Path, PathBuf};

/// Why an output was refused or a write failed; each variant keeps the files (and the I/O error)
/// its message names. `Display` is the message.
#[derive(Debug)]
pub enum AtomicIoError {
    /// An output prefix whose last component is empty, `.` or `..` (`--out dir/`).
    NoFileName {
        /// The prefix as given.
        prefix: PathBuf,
    },
    /// An output that is one of the run's inputs (writing it would destroy that input).
    OutputIsInput {
        /// Where the output comes from (`--out`, `--checkpoint-path`).
        flag: String,
        /// The output.
        output: PathBuf,
        /// What the input is (`the scene`, `--reference`).
        what: String,
        /// The input, as it was given.
        input: PathBuf,
    },
    /// Two outputs of the run that are the same file (one would overwrite the other).
    OutputTwice {
        /// Where the second output comes from.
        flag: String,
        /// The second output.
        output: PathBuf,
        /// Where the first one comes from.
        other_flag: String,
        /// The first output.
        other: PathBuf,
    },
    /// An output written through a temporary (`PATH.tmp`) or backup (`PATH.old`) that clashes
    /// with an input, another output or an existing file.
    Sibling {
        /// Where the output comes from.
        flag: String,
        /// The output.
        output: PathBuf,
        /// Which of its siblings clashes ([`Sibling::path`] names it).
        sibling: Sibling,
        /// What it clashes with.
        clash: SiblingClash,
    },
    /// An output that is a directory where a file is written, or a file where a directory is.
    WrongKind {
        /// Where the output comes from.
        flag: String,
        /// The output.
        output: PathBuf,
        /// True when a directory is wanted (and the path is a file).
        want_dir: bool,
    },
    /// An output under a path that is not a directory.
    NotCreatable {
        /// Where the output comes from.
        flag: String,
        /// The output.
        output: PathBuf,
        /// Its nearest existing ancestor, which is not a directory.
        blocker: PathBuf,
    },
    /// An output in a directory where no file can be created (no write permission, a read-only
    /// file system).
    NotWritable {
        /// Where the output comes from.
        flag: String,
        /// The output.
        output: PathBuf,
        /// The directory (the output's nearest existing ancestor).
        dir: PathBuf,
        /// The I/O error of the probe.
        source: io::Error,
    },
    /// An input of the command line (the scene file) that cannot be read: missing, not a regular
    /// file, no permission. It has no line: the message names the file alone.
    Unreadable {
        /// What the input is (`scene file`).
        what: String,
        /// The input, as given.
        path: PathBuf,
        /// The I/O error.
        source: io::Error,
    },
    /// An input inside a directory the run writes.
    InputInOutputDir {
        /// What the input is.
        what: String,
        /// The input.
        input: PathBuf,
        /// Where the directory comes from (`compare --out`).
        flag: String,
        /// The directory.
        dir: PathBuf,
    },
    /// A file of a set to write that is a directory.
    IsDirectory {
        /// The file.
        path: PathBuf,
    },
    /// A file named twice in one set.
    NamedTwice {
        /// The file.
        path: PathBuf,
    },
    /// A temporary that cannot be written (a full disk; one already there).
    Write {
        /// The temporary (`PATH.tmp`).
        path: PathBuf,
        /// The I/O error.
        source: io::Error,
    },
    /// The previous version of a file of a set cannot be kept as its backup.
    Backup {
        /// The file.
        path: PathBuf,
        /// Its backup (`PATH.old`).
        backup: PathBuf,
        /// The I/O error.
        source: io::Error,
    },
    /// A temporary cannot be renamed over its file; the files already replaced were put back,
    /// except those in `mixed`.
    Rename {
        /// The temporary.
        from: PathBuf,
        /// The file.
        to: PathBuf,
        /// The I/O error.
        source: io::Error,
        /// The files already replaced that could not be put back, each with its error (empty:
        /// the previous files are unchanged).
        mixed: Vec<(PathBuf, io::Error)>,
    },
}

/// The files an output is written through ([`AtomicIoError::Sibling`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sibling {
    /// The temporary, `PATH.tmp` ([`super::atomic_path`]).
    Temporary,
    /// The backup, `PATH.old` ([`super::backup_path`]).
    Backup,
}

impl Sibling {
    /// This sibling of `output`.
    pub fn path(self, output: &Path) -> PathBuf {
        match self {
            Sibling::Temporary => super::atomic_path(output),
            Sibling::Backup => super::backup_path(output),
        }
    }

    /// Its name in messages: `temporary` or `backup`.
    pub fn name(self) -> &'static str {
        match self {
            Sibling::Temporary => "temporary",
            Sibling::Backup => "backup",
        }
    }
}

/// What an output's temporary or backup clashes with ([`AtomicIoError::Sibling`]).
#[derive(Debug)]
pub enum SiblingClash {
    /// An input of the run: what it is, and the input as given.
    Input {
        /// What the input is.
        what: String,
        /// The input.
        path: PathBuf,
    },
    /// Another output of the run.
    Output,
    /// An existing file (left by an interrupted write?).
    Exists,
}

impl AtomicIoError {
    /// The file the error is about: the output, the input in an output directory, the file
    /// written (for a failed temporary, the temporary).
    pub fn path(&self) -> &Path {
        use AtomicIoError::*;
        match self {
            NoFileName { prefix } => prefix,
            OutputIsInput { output, .. }
            | OutputTwice { output, .. }
            | Sibling { output, .. }
            | WrongKind { output, .. }
            | NotCreatable { output, .. }
            | NotWritable { output, .. } => output,
            InputInOutputDir { input, .. } => input,
            Unreadable { path, .. } => path,
            IsDirectory { path } | NamedTwice { path } | Write { path, .. } | Backup { path, .. } => path,
            Rename { to, .. } => to,
        }
    }
}

impl std::fmt::Display for AtomicIoError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        use AtomicIoError::*;
        match self {
            NoFileName { prefix } => {
                let raw = prefix.as_os_str().to_string_lossy();
                write!(
                    f,
                    "output prefix `{raw}` has no file name (the files would be `{raw}.exr`, …); give one, e.g. \
                     `--out {}`",
                    Path::new(raw.as_ref()).join("render").display()
                )
            }
            OutputIsInput { flag, output, what, input } => write!(
                f,
                "{flag} `{}` is {what} `{}`: writing it would destroy it (name another output)",
                output.display(),
                input.display()
            ),
            OutputTwice { flag, output, other_flag, other } => write!(
                f,
                "{flag} `{}` is also the output `{}` ({other_flag}): one would overwrite the other",
                output.display(),
                other.display()
            ),
            Sibling { flag, output, sibling, clash } => {
                let (role, path) = (sibling.name(), sibling.path(output));
                write!(f, "{flag} `{}` is written through its {role} `{}`, which ", output.display(), path.display())?;
                match clash {
                    SiblingClash::Input { what, path } => {
                        write!(f, "is {what} `{}`: writing would destroy it (name another output)", path.display())
                    }
                    SiblingClash::Output => write!(f, "is also an output of this run (name another output)"),
                    SiblingClash::Exists => write!(
                        f,
                        "exists and is no stale temporary of a killed forecast write (another program's file, \
                         or a run writing this output now): it would be replaced and then deleted; move it away, \
                         or name another output"
                    ),
                }
            }
            WrongKind { flag, output, want_dir } => {
                let (is, want) = if *want_dir { ("a file", "directory") } else { ("a directory", "file") };
                write!(f, "{flag} `{}` is {is}; name a {want}", output.display())
            }
            NotCreatable { flag, output, blocker } => {
                write!(f, "{flag} `{}` cannot be created: `{}` is not a directory", output.display(), blocker.display())
            }
            NotWritable { flag, output, dir, source } => write!(
                f,
                "{flag} `{}` cannot be written: no file can be created in `{}` ({source}); name a writable \
                 directory (checked before any work)",
                output.display(),
                dir.display()
            ),
            Unreadable { what, path, source } => write!(f, "cannot read {what} `{}`: {source}", path.display()),
            InputInOutputDir { what, input, flag, dir } => write!(
                f,
                "{what} `{}` lies in `{}`, which {flag} writes: it could be overwritten (move it or name another \
                 output)",
                input.display(),
                dir.display()
            ),
            IsDirectory { path } => write!(f, "cannot write {}: it is a directory", path.display()),
            NamedTwice { path } => write!(f, "cannot write {}: named twice in one set", path.display()),
            Write { path, source } => write!(f, "cannot write {}: {source}", path.display()),
            Backup { path, backup, source } => {
                write!(f, "cannot keep the previous {} as {}: {source}", path.display(), backup.display())
            }
            Rename { from, to, source, mixed } => {
                write!(f, "cannot rename {} to {}: {source}", from.display(), to.display())?;
                if mixed.is_empty() {
                    return write!(f, " (the previous files are unchanged)");
                }
                write!(f, "; the set is now mixed: ")?;
                for (i, (p, e)) in mixed.iter().enumerate() {
                    let sep = if i == 0 { "" } else { "; " };
                    write!(f, "{sep}{} is the new version ({e})", p.display())?;
                }
                Ok(())
            }
        }
    }
}

impl std::error::Error for AtomicIoError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            AtomicIoError::Write { source, .. }
            | AtomicIoError::NotWritable { source, .. }
            | AtomicIoError::Unreadable { source, .. }
            | AtomicIoError::Backup { source, .. }
            | AtomicIoError::Rename { source, .. } => Some(source),
            _ => None,
        }
    }
}

/// For the callers whose own errors are still messages.
impl From<AtomicIoError> for String {
    fn from(e: AtomicIoError) -> String {
        e.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The messages are the ones users (and the tests in `tests/`) have always seen.
    #[test]
    fn messages_word_for_word() {
        let p = PathBuf::from;
        let io = |kind| io::Error::new(kind, "boom");
        let sibling = |clash| AtomicIoError::Sibling {
            flag: "--out".into(),
            output: p("r.json"),
            sibling: Sibling::Temporary,
            clash,
        };
        let cases: Vec<(AtomicIoError, &str)> = vec![
            (
                AtomicIoError::NoFileName { prefix: p("dir/") },
                "output prefix `dir/` has no file name (the files would be `dir/.exr`, …); give one, e.g. `--out \
                 dir/render`",
            ),
            (
                AtomicIoError::OutputIsInput {
                    flag: "--png".into(),
                    output: p("a.exr"),
                    what: "the image A".into(),
                    input: p("./a.exr"),
                },
                "--png `a.exr` is the image A `./a.exr`: writing it would destroy it (name another output)",
            ),
            (
                AtomicIoError::OutputTwice {
                    flag: "--checkpoint-path".into(),
                    output: p("r.exr"),
                    other_flag: "--out".into(),
                    other: p("./r.exr"),
                },
                "--checkpoint-path `r.exr` is also the output `./r.exr` (--out): one would overwrite the other",
            ),
            (
                sibling(SiblingClash::Input { what: "the scene".into(), path: p("r.json.tmp") }),
                "--out `r.json` is written through its temporary `r.json.tmp`, which is the scene `r.json.tmp`: \
                 writing would destroy it (name another output)",
            ),
            (
                sibling(SiblingClash::Output),
                "--out `r.json` is written through its temporary `r.json.tmp`, which is also an output of this run \
                 (name another output)",
            ),
            (
                sibling(SiblingClash::Exists),
                "--out `r.json` is written through its temporary `r.json.tmp`, which exists and is no stale \
                 temporary of a killed forecast write (another program's file, or a run writing this output now): it \
                 would be replaced and then deleted; move it away, or name another output",
            ),
            (
                AtomicIoError::NotWritable {
                    flag: "--out".into(),
                    output: p("ro/x.exr"),
                    dir: p("ro"),
                    source: io::Error::from(io::ErrorKind::PermissionDenied),
                },
                "--out `ro/x.exr` cannot be written: no file can be created in `ro` (permission denied); name a \
                 writable directory (checked before any work)",
            ),
            (
                AtomicIoError::Unreadable {
                    what: "scene file".into(),
                    path: p("s.toml"),
                    source: io::Error::from(io::ErrorKind::NotFound),
                },
                "cannot read scene file `s.toml`: entity not found",
            ),
            (
                AtomicIoError::WrongKind { flag: "--out".into(), output: p("d"), want_dir: false },
                "--out `d` is a directory; name a file",
            ),
            (
                AtomicIoError::WrongKind { flag: "compare --out".into(), output: p("f"), want_dir: true },
                "compare --out `f` is a file; name a directory",
            ),
            (
                AtomicIoError::NotCreatable { flag: "--out".into(), output: p("f/x.exr"), blocker: p("/w/f") },
                "--out `f/x.exr` cannot be created: `/w/f` is not a directory",
            ),
            (
                AtomicIoError::InputInOutputDir {
                    what: "--reference".into(),
                    input: p("o/ref.exr"),
                    flag: "compare --out".into(),
                    dir: p("o"),
                },
                "--reference `o/ref.exr` lies in `o`, which compare --out writes: it could be overwritten (move it \
                 or name another output)",
            ),
            (AtomicIoError::IsDirectory { path: p("r.json") }, "cannot write r.json: it is a directory"),
            (AtomicIoError::NamedTwice { path: p("r.json") }, "cannot write r.json: named twice in one set"),
            (
                AtomicIoError::Write { path: p("r.json.tmp"), source: io(io::ErrorKind::Other) },
                "cannot write r.json.tmp: boom",
            ),
            (
                AtomicIoError::Backup { path: p("r.exr"), backup: p("r.exr.old"), source: io(io::ErrorKind::Other) },
                "cannot keep the previous r.exr as r.exr.old: boom",
            ),
            (
                AtomicIoError::Rename {
                    from: p("r.png.tmp"),
                    to: p("r.png"),
                    source: io(io::ErrorKind::Other),
                    mixed: Vec::new(),
                },
                "cannot rename r.png.tmp to r.png: boom (the previous files are unchanged)",
            ),
            (
                AtomicIoError::Rename {
                    from: p("r.png.tmp"),
                    to: p("r.png"),
                    source: io(io::ErrorKind::Other),
                    mixed: vec![(p("r.exr"), io(io::ErrorKind::Other)), (p("r.json"), io(io::ErrorKind::Other))],
                },
                "cannot rename r.png.tmp to r.png: boom; the set is now mixed: r.exr is the new version (boom); \
                 r.json is the new version (boom)",
            ),
        ];
        for (e, want) in cases {
            assert_eq!(e.to_string(), want, "{e:?}");
        }
        let backup = AtomicIoError::Sibling {
            flag: "--out".into(),
            output: p("r.exr"),
            sibling: Sibling::Backup,
            clash: SiblingClash::Output,
        };
        assert!(backup.to_string().starts_with("--out `r.exr` is written through its backup `r.exr.old`, which "));
    }

    /// Small enough to return by value (clippy's `result_large_err`: 128 bytes).
    #[test]
    fn fits_in_a_result() {
        assert!(std::mem::size_of::<AtomicIoError>() <= 128, "{}", std::mem::size_of::<AtomicIoError>());
    }
}
