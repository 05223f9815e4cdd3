//! Reading optional numbers that only make sense in a range (a size, a fraction, a
//! confidence), so that a hand-written or foreign file with a negative diameter or a visibility
//! of 2 is refused with the field's name instead of quietly changing what is scored. Used by the
//! truth and detection records through `#[serde(deserialize_with = ...)]`.

use serde::{de::Error, Deserialize, Deserializer};

/// `diameter_m`: finite and greater than 0.
pub(crate) fn diameter_m<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
    positive(d, "diameter_m")
}

/// `radius_px`: finite and greater than 0.
pub(crate) fn radius_px<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
    positive(d, "radius_px")
}

/// `visibility`: in `[0, 1]`.
pub(crate) fn visibility<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
    fraction(d, "visibility")
}

/// `confidence`: in `[0, 1]`.
pub(crate) fn confidence<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
    fraction(d, "confidence")
}

fn fraction<'de, D: Deserializer<'de>>(d: D, name: &str) -> Result<Option<f64>, D::Error> {
    let v = Option::<f64>::deserialize(d)?;
    match v {
        Some(x) if !(0.0..=1.0).contains(&x) => Err(D::Error::custom(format!(
            "{name} must lie in [0, 1], got {x}"
        ))),
        _ => Ok(v),
    }
}

fn positive<'de, D: Deserializer<'de>>(d: D, name: &str) -> Result<Option<f64>, D::Error> {
    let v = Option::<f64>::deserialize(d)?;
    match v {
        Some(x) if !(x.is_finite() && x > 0.0) => Err(D::Error::custom(format!(
            "{name} must be a positive number, got {x}"
        ))),
        _ => Ok(v),
    }
}
