//! Parsing the generator's named choices (`kinect-v2`, `tof`, `mixed`...) from text, strictly: an
//! unknown name is an error that lists the known ones, never a silent default. Used by examples
//! and any program that takes these choices as arguments (`"d435".parse::<CameraPreset>()`).

use std::str::FromStr;

use crate::{CameraPreset, Domain, FruitChoice, FruitKind, LightPreset, NoiseModel};

/// The element of `all` whose `name` is `s`, or an error naming `what` and the known names.
fn by_name<T: Copy>(
    all: &[T],
    name: fn(T) -> &'static str,
    s: &str,
    what: &str,
) -> Result<T, String> {
    all.iter().copied().find(|&t| name(t) == s).ok_or_else(|| {
        let known: Vec<&str> = all.iter().map(|&t| name(t)).collect();
        format!("unknown {what} `{s}`; known: {}", known.join(", "))
    })
}

impl FromStr for CameraPreset {
    type Err = String;

    /// # Errors
    /// An unknown name (the message lists the known ones).
    fn from_str(s: &str) -> Result<Self, String> {
        by_name(&Self::ALL, Self::name, s, "camera")
    }
}

impl FromStr for NoiseModel {
    type Err = String;

    /// # Errors
    /// An unknown name (the message lists the known ones).
    fn from_str(s: &str) -> Result<Self, String> {
        by_name(&Self::ALL, Self::name, s, "noise model")
    }
}

impl FromStr for FruitChoice {
    type Err = String;

    /// A kind's name or `mixed`.
    ///
    /// # Errors
    /// An unknown name (the message lists the known ones).
    fn from_str(s: &str) -> Result<Self, String> {
        let mut all: Vec<FruitChoice> = FruitKind::ALL.into_iter().map(FruitChoice::Only).collect();
        all.push(FruitChoice::Mixed);
        by_name(&all, Self::name, s, "fruit")
    }
}

impl FromStr for LightPreset {
    type Err = String;

    /// # Errors
    /// An unknown name (the message lists the known ones).
    fn from_str(s: &str) -> Result<Self, String> {
        by_name(&Self::ALL, Self::name, s, "light preset")
    }
}

impl FromStr for Domain {
    type Err = String;

    /// # Errors
    /// An unknown name (the message lists the known ones).
    fn from_str(s: &str) -> Result<Self, String> {
        by_name(&Self::ALL, Self::name, s, "domain")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_typos_are_errors() {
        for c in CameraPreset::ALL {
            assert_eq!(c.name().parse::<CameraPreset>(), Ok(c));
        }
        for n in NoiseModel::ALL {
            assert_eq!(n.name().parse::<NoiseModel>(), Ok(n));
        }
        for l in LightPreset::ALL {
            assert_eq!(l.name().parse::<LightPreset>(), Ok(l));
        }
        for d in Domain::ALL {
            assert_eq!(d.name().parse::<Domain>(), Ok(d));
        }
        assert!("night"
            .parse::<LightPreset>()
            .unwrap_err()
            .contains("low-sun"));
        assert_eq!("mixed".parse::<FruitChoice>(), Ok(FruitChoice::Mixed));
        assert_eq!(
            "guava".parse::<FruitChoice>(),
            Ok(FruitChoice::Only(FruitKind::Guava))
        );
        let err = "kinect2".parse::<CameraPreset>().unwrap_err();
        assert!(
            err.contains("kinect2") && err.contains("kinect-v2"),
            "{err}"
        );
        assert!("tof2".parse::<NoiseModel>().is_err());
        assert!("pepers".parse::<FruitChoice>().is_err());
    }
}
