//! One error type for the whole crate, with a few kinds a caller can act on.
//!
//! Every message names the thing that is wrong (a file, a field, a value) and,
//! where it helps, what is allowed instead.

use std::path::PathBuf;

/// Everything that can go wrong in solidtex.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The operating system refused a read or a write.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file or folder involved.
        path: PathBuf,
        /// What the operating system said.
        source: std::io::Error,
    },
    /// A file exists but its content is corrupt, truncated or unsupported.
    #[error("{}: {message}", path.display())]
    File {
        /// The file involved.
        path: PathBuf,
        /// What is wrong with it.
        message: String,
    },
    /// A parameter or value is outside what is allowed.
    #[error("{0}")]
    Invalid(String),
    /// One of the exemplars of a synthesis is unfit: `which` is 0 for the exemplar (Ex),
    /// 1 for Ey, 2 for Ez, so that a caller who knows their files names the one at fault.
    #[error("{message}")]
    Exemplar {
        /// 0, 1 or 2: the exemplar orthogonal to x, y or z.
        which: usize,
        /// What is wrong with it.
        message: String,
    },
    /// A command-line option or argument is malformed or out of its range (exit code 2).
    #[error("{0}")]
    Usage(String),
    /// A volume would need more memory than the voxel budget allows.
    #[error(
        "a {}x{}x{} volume with {channels} channel(s) needs {needed} bytes, over the voxel budget of {budget} bytes \
         (raise it with SOLIDTEX_MAX_BYTES or choose smaller dims)",
        dims[0], dims[1], dims[2]
    )]
    Budget {
        /// The requested dims.
        dims: [usize; 3],
        /// The requested channel count.
        channels: usize,
        /// Bytes the volume would need (saturating).
        needed: u128,
        /// The budget in bytes.
        budget: u128,
    },
    /// Long work was cancelled through [`crate::progress::Progress`].
    #[error("cancelled")]
    Cancelled,
}

/// For a path holding a NUL byte, which no file name may hold (so no file there can be read
/// or written) and which a terminal does not show: the error to give instead, quoting the
/// path with the byte as `\0`.
fn nul_in_name(path: &std::path::Path) -> Option<Error> {
    path.as_os_str().as_encoded_bytes().contains(&0).then(|| {
        Error::Invalid(format!("the file name {path:?} holds a NUL byte (shown as \\0); no file name may contain one"))
    })
}

/// The crate's result alias.
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    /// An [`Error::Invalid`] from anything printable.
    pub fn invalid(message: impl Into<String>) -> Self {
        Error::Invalid(message.into())
    }

    /// An [`Error::Exemplar`] about exemplar `which` (0: Ex, 1: Ey, 2: Ez).
    pub fn exemplar(which: usize, message: impl Into<String>) -> Self {
        Error::Exemplar { which, message: message.into() }
    }

    /// An [`Error::Usage`]: a command-line value the user must correct.
    pub fn usage(message: impl Into<String>) -> Self {
        Error::Usage(message.into())
    }

    /// The process exit code for this error: 2 for usage errors, else 1.
    pub fn exit_code(&self) -> u8 {
        match self {
            Error::Usage(_) => 2,
            _ => 1,
        }
    }

    /// An [`Error::File`] for `path` with `message`.
    pub fn file(path: impl Into<PathBuf>, message: impl Into<String>) -> Self {
        let path = path.into();
        nul_in_name(&path).unwrap_or(Error::File { path, message: message.into() })
    }

    /// An [`Error::Io`] for `path`.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        let path = path.into();
        nul_in_name(&path).unwrap_or(Error::Io { path, source })
    }

    /// Prefix the error with the file it came from, when it has none yet.
    pub fn in_file(self, path: impl Into<PathBuf>) -> Self {
        match self {
            Error::Invalid(message) | Error::Exemplar { message, .. } => Error::file(path, message),
            budget @ Error::Budget { .. } => Error::file(path, budget.to_string()),
            other => other,
        }
    }
}
