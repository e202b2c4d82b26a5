//! Parsing of the numeric option values the subcommands share.

use crate::UserError;

/// A comma-separated list of `min..=max` finite numbers.
pub(crate) fn parse_list(text: &str, option: &str, min: usize, max: usize) -> Result<Vec<f64>, UserError> {
    let values: Vec<f64> = text
        .split(',')
        .map(|x| x.trim().parse::<f64>().ok().filter(|x| x.is_finite()))
        .collect::<Option<_>>()
        .ok_or_else(|| UserError(format!("{option} {text}: expected comma-separated finite numbers")))?;
    if values.len() < min || values.len() > max {
        let count = if min == max { format!("{min}") } else { format!("{min} or {max}") };
        return Err(UserError(format!("{option} {text}: expected {count} numbers, got {}", values.len())));
    }
    Ok(values)
}

/// An image size `W,H`: two integers from 1 to `max`.
pub(crate) fn parse_size(text: &str, option: &str, max: u32) -> Result<[u32; 2], UserError> {
    let sides = parse_list(text, option, 2, 2)?;
    let rule = if max == u32::MAX { "positive integers".to_string() } else { format!("integers from 1 to {max}") };
    let side = |x: f64| {
        (x >= 1.0 && x <= f64::from(max) && x.fract() == 0.0)
            .then_some(x as u32)
            .ok_or_else(|| UserError(format!("{option} {text}: sides must be {rule}")))
    };
    Ok([side(sides[0])?, side(sides[1])?])
}
