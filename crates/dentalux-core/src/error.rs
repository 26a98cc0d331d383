//! Errors of the core: bad input that names the field and the range it must lie in,
//! and cancellation by the caller.

use std::fmt;

/// Everything the core can refuse or stop for.
#[derive(Debug, Clone, PartialEq)]
pub enum Error {
    /// A value outside its allowed range; the message names field, value and range.
    InvalidInput(String),
    /// The caller asked the computation to stop (e.g. Ctrl-C).
    Cancelled,
}

/// Result alias used throughout the core.
pub type Result<T> = std::result::Result<T, Error>;

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::InvalidInput(msg) => write!(f, "{msg}"),
            Error::Cancelled => write!(f, "cancelled"),
        }
    }
}

impl std::error::Error for Error {}

/// Check that `value` is finite and > 0 (lengths, sizes): [`check_range`] over (0, inf).
pub fn check_positive(field: &str, value: f64, unit: &str) -> Result<()> {
    check_range(field, value, 0.0, true, f64::INFINITY, true, unit)
}

/// Check that `value` is finite and inside `[lo, hi]` (bounds open where `*_open` is set).
pub fn check_range(
    field: &str,
    value: f64,
    lo: f64,
    lo_open: bool,
    hi: f64,
    hi_open: bool,
    unit: &str,
) -> Result<()> {
    let above = if lo_open { value > lo } else { value >= lo };
    let below = if hi_open { value < hi } else { value <= hi };
    if value.is_finite() && above && below {
        return Ok(());
    }
    let l = if lo_open { "(" } else { "[" };
    let r = if hi_open { ")" } else { "]" };
    let hi_s = if hi.is_infinite() {
        "inf".to_string()
    } else {
        format!("{hi}")
    };
    let unit_s = if unit.is_empty() {
        String::new()
    } else {
        format!(" {unit}")
    };
    Err(Error::InvalidInput(format!(
        "{field} = {value} is out of range: allowed {l}{lo}, {hi_s}{r}{unit_s}"
    )))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn range_messages_name_field_and_bounds() {
        assert!(check_range("g", 0.5, -1.0, true, 1.0, true, "").is_ok());
        let e = check_range("layers[0].g", 1.0, -1.0, true, 1.0, true, "").unwrap_err();
        assert_eq!(
            e.to_string(),
            "layers[0].g = 1 is out of range: allowed (-1, 1)"
        );
        let e = check_range("mua", f64::NAN, 0.0, false, f64::INFINITY, true, "1/mm").unwrap_err();
        assert!(e.to_string().contains("mua = NaN"));
        assert!(e.to_string().contains("[0, inf) 1/mm"));
    }
}
