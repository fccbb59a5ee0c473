//! `MethodError`: why a method refused its options or its preprocess product (`Display` is the
//! message).

use super::Method;

/// Why a method refused its options or its preprocess product (the errors of [`MethodArgs`]'s
/// checks, [`Method::preprocess`] and [`Method::build`]); `Display` is the message.
#[derive(Clone, Debug, PartialEq)]
pub enum MethodError {
    /// An option's value refused: `--photons 0: photons must be at least 1 (got 0)`, or without
    /// the value, `--path-filter: ...`.
    Option {
        /// The flag (`--photons`; `--ris-candidates/--ris-survivors` for a pair).
        flag: &'static str,
        /// The value refused, where the message names it.
        value: Option<String>,
        /// Why.
        reason: String,
    },
    /// A flag of another method: `--clusters belongs to iws-cf/pt-cf, not pt`.
    ForeignFlag {
        /// The flag, `--clusters`.
        flag: String,
        /// The methods that take it, `iws-cf/pt-cf`.
        owners: String,
        /// The method that does not.
        method: Method,
    },
    /// A back end this build lacks (`--accel embree` without Embree): `accel`'s message.
    Backend(String),
    /// The broadcast preprocess product does not decode.
    Product {
        /// The method whose product it is.
        method: Method,
        /// Its length in bytes.
        bytes: usize,
        /// The decoder's message.
        reason: String,
    },
    /// A decoded product that is inconsistent (the message names the product).
    BadProduct(String),
}

impl MethodError {
    /// Option `flag` refused for `reason` (the message does not repeat the value).
    pub fn option(flag: &'static str, reason: impl std::fmt::Display) -> MethodError {
        MethodError::Option { flag, value: None, reason: reason.to_string() }
    }

    /// `value` of option `flag` against `limit` (`crate::param_limits`).
    pub fn check_limit(limit: &crate::param_limits::Limit, flag: &'static str, value: u64) -> Result<(), MethodError> {
        limit.check(value).map_err(|reason| MethodError::Option { flag, value: Some(value.to_string()), reason })
    }
}

impl std::fmt::Display for MethodError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            MethodError::Option { flag, value: Some(v), reason } => write!(f, "{flag} {v}: {reason}"),
            MethodError::Option { flag, value: None, reason } => write!(f, "{flag}: {reason}"),
            MethodError::ForeignFlag { flag, owners, method } => {
                write!(f, "{flag} belongs to {owners}, not {}", method.name())
            }
            MethodError::Backend(m) | MethodError::BadProduct(m) => write!(f, "{m}"),
            MethodError::Product { method, bytes, reason } => {
                write!(f, "{}: cannot decode the broadcast preprocess product ({bytes} bytes): {reason}", method.name())
            }
        }
    }
}

impl std::error::Error for MethodError {}

/// For the callers whose own errors are still messages.
impl From<MethodError> for String {
    fn from(e: MethodError) -> String {
        e.to_string()
    }
}
