//! Mapping the `vertex` element's properties to point-cloud columns (positions, colours,
//! normals, intensities, labels), and collecting those columns row by row.

use pomona_core::nalgebra::{Point3, Vector3};

use super::rows::Num;
use super::{PlyElement, PlyEncoding, PlyError, PlyPropertyKind, PlyType};
use crate::pcd::clip;

/// Vertex property indices that map to cloud attributes.
#[derive(Debug, Default)]
pub(super) struct VertexPlan {
    pub(super) xyz: [Option<usize>; 3],
    pub(super) rgb: [Option<usize>; 3],
    pub(super) normal: [Option<usize>; 3],
    pub(super) intensity: Option<usize>,
    pub(super) label: Option<usize>,
}

impl VertexPlan {
    pub(super) fn new(vertex: &PlyElement) -> Result<Self, PlyError> {
        let mut plan = VertexPlan::default();
        for (i, p) in vertex.properties.iter().enumerate() {
            let lower = p.name.to_ascii_lowercase();
            let slot = match lower.as_str() {
                "x" => &mut plan.xyz[0],
                "y" => &mut plan.xyz[1],
                "z" => &mut plan.xyz[2],
                "red" | "r" | "diffuse_red" => &mut plan.rgb[0],
                "green" | "g" | "diffuse_green" => &mut plan.rgb[1],
                "blue" | "b" | "diffuse_blue" => &mut plan.rgb[2],
                "nx" | "normal_x" => &mut plan.normal[0],
                "ny" | "normal_y" => &mut plan.normal[1],
                "nz" | "normal_z" => &mut plan.normal[2],
                "intensity" | "scalar_intensity" | "scalar" => &mut plan.intensity,
                "label" => &mut plan.label,
                _ => continue,
            };
            if matches!(p.kind, PlyPropertyKind::List { .. }) {
                return Err(PlyError::UnsupportedProperty {
                    name: clip(&p.name),
                    reason: "must be a scalar, not a list",
                });
            }
            if slot.replace(i).is_some() {
                return Err(PlyError::DuplicateProperty {
                    element: clip(&vertex.name),
                    name: clip(&p.name),
                });
            }
        }
        for (slot, name) in plan.xyz.iter().zip(["x", "y", "z"]) {
            if slot.is_none() {
                return Err(PlyError::MissingProperty(name));
            }
        }
        for (group, names) in [
            (&plan.rgb, ["red", "green", "blue"]),
            (&plan.normal, ["nx", "ny", "nz"]),
        ] {
            if group.iter().any(Option::is_some) {
                if let Some((_, name)) = group.iter().zip(names).find(|(s, _)| s.is_none()) {
                    return Err(PlyError::MissingProperty(name));
                }
            }
        }
        Ok(plan)
    }
}

/// Minimum bytes one row of `element` occupies in `encoding`.
pub(super) fn min_row_bytes(element: &PlyElement, encoding: PlyEncoding) -> u64 {
    match encoding {
        PlyEncoding::Ascii => 2 * element.properties.len() as u64,
        _ => element
            .properties
            .iter()
            .map(|p| match p.kind {
                PlyPropertyKind::Scalar(t) => t.size() as u64,
                PlyPropertyKind::List { count, .. } => count.size() as u64,
            })
            .sum(),
    }
}

/// The cloud columns of the vertices read so far.
pub(super) struct Vertices {
    pub(super) points: Vec<Point3<f32>>,
    pub(super) colors: Option<Vec<[u8; 3]>>,
    pub(super) normals: Option<Vec<Vector3<f32>>>,
    pub(super) intensities: Option<Vec<f32>>,
    pub(super) labels: Option<Vec<u32>>,
}

impl Vertices {
    /// Bytes the columns of one vertex take.
    pub(super) fn bytes_per_vertex(plan: &VertexPlan) -> u64 {
        let size = |present: bool, bytes: usize| if present { bytes as u64 } else { 0 };
        size(true, std::mem::size_of::<Point3<f32>>())
            + size(plan.rgb[0].is_some(), std::mem::size_of::<[u8; 3]>())
            + size(
                plan.normal[0].is_some(),
                std::mem::size_of::<Vector3<f32>>(),
            )
            + size(plan.intensity.is_some(), std::mem::size_of::<f32>())
            + size(plan.label.is_some(), std::mem::size_of::<u32>())
    }

    pub(super) fn with_capacity(plan: &VertexPlan, n: usize) -> Self {
        Vertices {
            points: Vec::with_capacity(n),
            colors: plan.rgb[0].map(|_| Vec::with_capacity(n)),
            normals: plan.normal[0].map(|_| Vec::with_capacity(n)),
            intensities: plan.intensity.map(|_| Vec::with_capacity(n)),
            labels: plan.label.map(|_| Vec::with_capacity(n)),
        }
    }

    /// Appends vertex `row`, whose property `i` is `get(Some(i))`.
    pub(super) fn push(
        &mut self,
        plan: &VertexPlan,
        color_types: &[PlyType; 3],
        row: u64,
        get: impl Fn(Option<usize>) -> Option<Num>,
    ) -> Result<(), PlyError> {
        let f = |i: Option<usize>| get(i).map_or(f32::NAN, Num::to_f32);
        self.points
            .push(Point3::new(f(plan.xyz[0]), f(plan.xyz[1]), f(plan.xyz[2])));
        if let Some(colors) = &mut self.colors {
            let ch = |k: usize| get(plan.rgb[k]).map_or(0, |v| v.to_channel(color_types[k]));
            colors.push([ch(0), ch(1), ch(2)]);
        }
        if let Some(normals) = &mut self.normals {
            normals.push(Vector3::new(
                f(plan.normal[0]),
                f(plan.normal[1]),
                f(plan.normal[2]),
            ));
        }
        if let Some(intensities) = &mut self.intensities {
            intensities.push(f(plan.intensity));
        }
        if let Some(labels) = &mut self.labels {
            let value = get(plan.label).unwrap_or(Num::I(0));
            labels.push(value.to_label().ok_or(PlyError::LabelOutOfRange {
                vertex: row,
                value: value.as_f64(),
            })?);
        }
        Ok(())
    }
}
