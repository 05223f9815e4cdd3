//! Options that take two numbers, `A,B` (`--distance-m MIN,MAX`, `--reach-m NEAR,FAR`,
//! `--depth-range-m NEAR,FAR`, `--distortion K1,K2`): one parser, so they all read and complain
//! alike.

/// Parses `A,B` into two finite numbers; `example` shows the form in the error message.
///
/// # Errors
/// A message naming the expected form or the part that is not a finite number.
pub fn parse_number_pair(s: &str, example: &str) -> Result<(f64, f64), String> {
    let (a, b) = s
        .split_once(',')
        .ok_or_else(|| format!("expected two numbers as {example}, got `{s}`"))?;
    let num = |t: &str| {
        t.trim()
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| format!("`{t}` is not a finite number"))
    };
    Ok((num(a)?, num(b)?))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pairs_parse_and_bad_ones_name_the_form() {
        assert_eq!(parse_number_pair("0.5, 2", "A,B").unwrap(), (0.5, 2.0));
        assert_eq!(parse_number_pair("-0.2,0.05", "A,B").unwrap(), (-0.2, 0.05));
        assert!(parse_number_pair("0.5", "NEAR,FAR")
            .unwrap_err()
            .contains("NEAR,FAR"));
        assert!(parse_number_pair("x,1", "A,B").unwrap_err().contains("`x`"));
        assert!(parse_number_pair("1,inf", "A,B").is_err());
    }
}
