//! Ground truth for one frame: which fruit are there, where, how big, how visible.
//!
//! Every geometric field is optional because real annotations are partial (a caliper diameter and
//! a 2D box but no 3D centre, say). Keys this version does not know are kept in `extra` and written
//! back unchanged, so tools can round-trip files made by newer tools or by hand.

use nalgebra::{Point2, Point3, Unit, Vector3};
use serde::{Deserialize, Serialize};

use crate::{ImageCircle, PinholeCamera, PixelBox};

/// Annotation of one frame (`truth/<frame>.json`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FrameTruth {
    /// `true` when every fruit in the frame is annotated; `false` means unannotated fruit exist,
    /// so precision cannot be measured on this frame.
    pub complete: bool,
    /// The annotated fruit.
    #[serde(default)]
    pub fruits: Vec<FruitTruth>,
    /// Keys not part of the format, kept verbatim.
    #[serde(flatten)]
    pub extra: serde_json::Map<String, serde_json::Value>,
}

/// One annotated fruit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FruitTruth {
    /// Identifier, unique within the frame (stable across frames when the source tracks fruit).
    pub id: String,
    /// Fruit kind, for example `"pepper"` or `"apple"`.
    pub kind: String,
    /// Centre of the whole fruit body in the camera frame, metres.
    #[serde(default)]
    pub center_m: Option<Point3<f64>>,
    /// Largest equatorial diameter, metres (positive; a file with another value is refused).
    #[serde(default, deserialize_with = "crate::range_checked::diameter_m")]
    pub diameter_m: Option<f64>,
    /// Unit symmetry axis in the camera frame (its reflection-symmetry planes contain it).
    #[serde(default, with = "unit_axis")]
    pub axis: Option<Unit<Vector3<f64>>>,
    /// Box around the visible pixels.
    #[serde(default)]
    pub bbox_px: Option<PixelBox>,
    /// Centre of the fruit's circle in the image, pixels (the whole fruit's outline, hidden
    /// parts included), when annotated in 2D or written by `pomona synth`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub center_px: Option<Point2<f64>>,
    /// Radius of that circle, pixels (positive).
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "crate::range_checked::radius_px"
    )]
    pub radius_px: Option<f64>,
    /// Visible pixels divided by the pixels the fruit would cover alone, in `[0, 1]`.
    #[serde(default, deserialize_with = "crate::range_checked::visibility")]
    pub visibility: Option<f64>,
    /// Keys not part of the format, kept verbatim.
    #[serde(flatten)]
    pub extra: serde_json::Map<String, serde_json::Value>,
}

impl FrameTruth {
    /// Keeps only the fruit whose kind is one of `kinds` (every fruit when `kinds` is empty: no
    /// filter), for scoring one kind of a mixed annotation; returns how many were left out.
    ///
    /// ```
    /// # use pomona_core::FrameTruth;
    /// let mut truth: FrameTruth = serde_json::from_str(
    ///     r#"{"complete": true, "fruits": [{"id": "1", "kind": "apple"}, {"id": "2", "kind": "leaf"}]}"#,
    /// ).unwrap();
    /// assert_eq!(truth.keep_kinds(&["apple"]), 1);
    /// assert_eq!(truth.fruits.len(), 1);
    /// ```
    pub fn keep_kinds<S: AsRef<str>>(&mut self, kinds: &[S]) -> usize {
        if kinds.is_empty() {
            return 0;
        }
        let before = self.fruits.len();
        self.fruits
            .retain(|f| kinds.iter().any(|k| k.as_ref() == f.kind));
        before - self.fruits.len()
    }
}

impl FruitTruth {
    /// The fruit's circle in the image: `center_px`/`radius_px` when annotated, else the sphere
    /// `center_m` ⌀ `diameter_m` projected, else the box's inscribed circle
    /// ([`ImageCircle::from_parts`]); `None` when the fruit cannot be placed in the image.
    pub fn image_circle(&self, camera: &PinholeCamera) -> Option<ImageCircle> {
        ImageCircle::from_parts(
            camera,
            self.center_px,
            self.radius_px,
            self.center_m.zip(self.diameter_m),
            self.bbox_px.as_ref(),
        )
    }
}

/// Serde for an optional unit vector stored as a plain `[x, y, z]` array. Reading normalises and
/// rejects zero or non-finite vectors, so a `Unit` is always a unit.
pub(crate) mod unit_axis {
    use nalgebra::{Unit, Vector3};
    use serde::{de::Error, Deserialize, Deserializer, Serialize, Serializer};

    pub fn serialize<S: Serializer>(
        v: &Option<Unit<Vector3<f64>>>,
        s: S,
    ) -> Result<S::Ok, S::Error> {
        v.map(|u| [u.x, u.y, u.z]).serialize(s)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(
        d: D,
    ) -> Result<Option<Unit<Vector3<f64>>>, D::Error> {
        let Some(a) = Option::<[f64; 3]>::deserialize(d)? else {
            return Ok(None);
        };
        let v = Vector3::from(a);
        let n = v.norm();
        if !(n.is_finite() && n > 0.0) {
            return Err(D::Error::custom("axis must be a finite non-zero vector"));
        }
        // A vector that is already unit to rounding (what the writers produce) is kept bit for
        // bit, so a detection read back equals the one written; dividing by a norm of 1 ± 1 ulp
        // would move its last digits.
        if (n - 1.0).abs() <= UNIT_TOLERANCE {
            return Ok(Some(Unit::new_unchecked(v)));
        }
        Ok(Some(Unit::new_unchecked(v / n)))
    }

    /// Largest `|‖v‖ − 1|` of a vector taken as unit without renormalising.
    const UNIT_TOLERANCE: f64 = 1e-12;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_partial_annotations_and_keeps_unknown_keys() {
        let json = r#"{"complete": false, "note": "hand made",
            "fruits": [{"id": "7", "kind": "apple", "bbox_px": [1, 2, 30, 40],
                        "diameter_m": 0.07, "height_m": 0.068, "center_m": null}]}"#;
        let t: FrameTruth = serde_json::from_str(json).unwrap();
        assert!(!t.complete);
        assert_eq!(t.extra["note"], "hand made");
        let f = &t.fruits[0];
        assert_eq!(f.center_m, None);
        assert_eq!(f.bbox_px.unwrap().xmax, 30.0);
        assert_eq!(f.extra["height_m"], 0.068);
        let back: FrameTruth = serde_json::from_str(&serde_json::to_string(&t).unwrap()).unwrap();
        assert_eq!(back, t);
    }

    #[test]
    fn axis_is_normalised_and_zero_axis_rejected() {
        let json = r#"{"id": "a", "kind": "eggplant", "axis": [0, 3, 4]}"#;
        let f: FruitTruth = serde_json::from_str(json).unwrap();
        let a = f.axis.unwrap();
        assert!((a.y - 0.6).abs() < 1e-12 && (a.z - 0.8).abs() < 1e-12);
        let bad = r#"{"id": "a", "kind": "eggplant", "axis": [0, 0, 0]}"#;
        assert!(serde_json::from_str::<FruitTruth>(bad).is_err());
    }

    /// An axis written by a detector (unit to rounding, not exactly) reads back bit for bit;
    /// renormalising it would change its last digits (the shape-fit cylinder axis of a
    /// `pomona detect` file once differed from the library's in the 16th digit).
    #[test]
    fn a_written_unit_axis_reads_back_unchanged() {
        // The axis of that detection, as the cylinder fit left it.
        let v = Vector3::new(
            -0.846_731_198_236_334_1,
            0.329_721_428_434_830_6,
            -0.417_528_511_079_371_3,
        );
        let axis = Unit::new_unchecked(v);
        let written = FruitTruth {
            axis: Some(axis),
            ..serde_json::from_str(r#"{"id": "a", "kind": "eggplant"}"#).unwrap()
        };
        let read: FruitTruth =
            serde_json::from_str(&serde_json::to_string(&written).unwrap()).unwrap();
        assert_eq!(read.axis, Some(axis));
        // Renormalising it moves its last digits, so without the tolerance this test fails.
        assert_ne!(v / v.norm(), v);
    }

    #[test]
    fn sizes_and_visibility_out_of_range_are_refused_by_name() {
        let fruit = |fields: &str| {
            serde_json::from_str::<FruitTruth>(&format!(r#"{{"id": "a", "kind": "x", {fields}}}"#))
        };
        for (fields, said) in [
            (
                r#""diameter_m": -0.07"#,
                "diameter_m must be a positive number",
            ),
            (r#""diameter_m": 0"#, "diameter_m"),
            (r#""radius_px": -3"#, "radius_px must be a positive number"),
            (r#""visibility": 1.5"#, "visibility"),
            (r#""visibility": -0.1"#, "visibility"),
        ] {
            let err = fruit(fields).expect_err(fields).to_string();
            assert!(err.contains(said), "{fields}: {err}");
        }
        // The ends of the ranges and absent or null fields read.
        let ok = fruit(r#""diameter_m": 0.07, "radius_px": 12.5, "visibility": 1"#).unwrap();
        assert_eq!(
            (ok.diameter_m, ok.radius_px, ok.visibility),
            (Some(0.07), Some(12.5), Some(1.0))
        );
        assert_eq!(
            fruit(r#""visibility": 0, "diameter_m": null"#)
                .unwrap()
                .visibility,
            Some(0.0)
        );
    }

    #[test]
    fn inverted_box_is_rejected() {
        let bad = r#"{"id": "a", "kind": "x", "bbox_px": [10, 0, 5, 4]}"#;
        assert!(serde_json::from_str::<FruitTruth>(bad).is_err());
    }
}
