//! Point clouds, organised (an H×W grid that mirrors the image it came from) or not.
//!
//! One type with a [`CloudLayout`] rather than two types, as in PCL: file formats, exporters and
//! most algorithms treat both alike, and grid-aware algorithms ask [`PointCloud::grid`] for the
//! dimensions. Optional attributes are parallel arrays so a stage that only needs positions never
//! touches colour.

use nalgebra::{Point3, Vector3};

use crate::CoreError;

/// How the points of a cloud are arranged.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CloudLayout {
    /// A list of points without neighbourhood structure.
    Unorganized,
    /// A row-major `height × width` grid; point `v * width + u` came from pixel `(u, v)`.
    Organized {
        /// Columns.
        width: u32,
        /// Rows.
        height: u32,
    },
}

/// A point cloud in one frame (usually the camera's), metres.
///
/// Invalid points (no depth) are kept as all-`NaN` positions so organised clouds keep their grid.
/// Every present attribute array has exactly one entry per point.
#[derive(Debug, Clone, PartialEq)]
pub struct PointCloud {
    layout: CloudLayout,
    points: Vec<Point3<f32>>,
    colors: Option<Vec<[u8; 3]>>,
    normals: Option<Vec<Vector3<f32>>>,
    labels: Option<Vec<u32>>,
    intensities: Option<Vec<f32>>,
}

impl PointCloud {
    /// An unorganised cloud of positions.
    pub fn unorganized(points: Vec<Point3<f32>>) -> Self {
        Self {
            layout: CloudLayout::Unorganized,
            points,
            colors: None,
            normals: None,
            labels: None,
            intensities: None,
        }
    }

    /// An organised cloud of `width × height` positions, row-major.
    ///
    /// # Errors
    /// [`CoreError::SizeMismatch`] when `points.len() != width * height`.
    pub fn organized(width: u32, height: u32, points: Vec<Point3<f32>>) -> Result<Self, CoreError> {
        let expected = width as usize * height as usize;
        if points.len() != expected {
            return Err(CoreError::SizeMismatch {
                what: "organised cloud points",
                width,
                height,
                expected,
                actual: points.len(),
            });
        }
        let mut cloud = Self::unorganized(points);
        cloud.layout = CloudLayout::Organized { width, height };
        Ok(cloud)
    }

    /// An organised cloud whose sizes the caller has already checked (a frame's own pixels).
    pub(crate) fn from_checked_parts(
        width: u32,
        height: u32,
        points: Vec<Point3<f32>>,
        colors: Option<Vec<[u8; 3]>>,
    ) -> Self {
        debug_assert_eq!(points.len(), width as usize * height as usize);
        debug_assert!(colors.as_ref().is_none_or(|c| c.len() == points.len()));
        let mut cloud = Self::unorganized(points);
        cloud.layout = CloudLayout::Organized { width, height };
        cloud.colors = colors;
        cloud
    }

    fn check_len(&self, what: &'static str, actual: usize) -> Result<(), CoreError> {
        if actual == self.points.len() {
            return Ok(());
        }
        let (width, height) = match self.layout {
            CloudLayout::Organized { width, height } => (width, height),
            CloudLayout::Unorganized => (self.points.len() as u32, 1),
        };
        Err(CoreError::SizeMismatch {
            what,
            width,
            height,
            expected: self.points.len(),
            actual,
        })
    }

    /// Attaches one RGB colour per point.
    ///
    /// # Errors
    /// [`CoreError::SizeMismatch`] when the count differs from the number of points.
    pub fn with_colors(mut self, colors: Vec<[u8; 3]>) -> Result<Self, CoreError> {
        self.check_len("cloud colours", colors.len())?;
        self.colors = Some(colors);
        Ok(self)
    }

    /// Attaches one normal per point (`NaN` where undefined).
    ///
    /// # Errors
    /// [`CoreError::SizeMismatch`] when the count differs from the number of points.
    pub fn with_normals(mut self, normals: Vec<Vector3<f32>>) -> Result<Self, CoreError> {
        self.check_len("cloud normals", normals.len())?;
        self.normals = Some(normals);
        Ok(self)
    }

    /// Attaches one integer label per point (segment or instance id).
    ///
    /// # Errors
    /// [`CoreError::SizeMismatch`] when the count differs from the number of points.
    pub fn with_labels(mut self, labels: Vec<u32>) -> Result<Self, CoreError> {
        self.check_len("cloud labels", labels.len())?;
        self.labels = Some(labels);
        Ok(self)
    }

    /// Attaches one intensity per point.
    ///
    /// # Errors
    /// [`CoreError::SizeMismatch`] when the count differs from the number of points.
    pub fn with_intensities(mut self, intensities: Vec<f32>) -> Result<Self, CoreError> {
        self.check_len("cloud intensities", intensities.len())?;
        self.intensities = Some(intensities);
        Ok(self)
    }

    /// The arrangement of the points.
    pub fn layout(&self) -> CloudLayout {
        self.layout
    }

    /// `(width, height)` when organised.
    pub fn grid(&self) -> Option<(u32, u32)> {
        match self.layout {
            CloudLayout::Organized { width, height } => Some((width, height)),
            CloudLayout::Unorganized => None,
        }
    }

    /// Number of points, valid or not.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Whether the cloud has no points at all.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Positions, metres.
    pub fn points(&self) -> &[Point3<f32>] {
        &self.points
    }

    /// Per-point colours, if present.
    pub fn colors(&self) -> Option<&[[u8; 3]]> {
        self.colors.as_deref()
    }

    /// Per-point normals, if present.
    pub fn normals(&self) -> Option<&[Vector3<f32>]> {
        self.normals.as_deref()
    }

    /// Per-point labels, if present.
    pub fn labels(&self) -> Option<&[u32]> {
        self.labels.as_deref()
    }

    /// Per-point intensities, if present.
    pub fn intensities(&self) -> Option<&[f32]> {
        self.intensities.as_deref()
    }

    /// Whether point `i` has a finite position.
    pub fn is_valid(&self, i: usize) -> bool {
        self.points
            .get(i)
            .is_some_and(|p| p.iter().all(|c| c.is_finite()))
    }

    /// Number of points with finite positions.
    pub fn valid_count(&self) -> usize {
        self.points
            .iter()
            .filter(|p| p.iter().all(|c| c.is_finite()))
            .count()
    }

    /// The point at grid position `(u, v)` of an organised cloud.
    pub fn at(&self, u: u32, v: u32) -> Option<&Point3<f32>> {
        let (w, h) = self.grid()?;
        (u < w && v < h).then(|| &self.points[v as usize * w as usize + u as usize])
    }

    /// Replaces every position by `f(position)`, keeping layout and attributes (for example to
    /// transform a cloud, or to invalidate points by returning `NaN`).
    pub fn map_points(mut self, f: impl Fn(&Point3<f32>) -> Point3<f32>) -> Self {
        for p in &mut self.points {
            *p = f(p);
        }
        self
    }

    /// A copy without invalid points (the layout becomes unorganised).
    pub fn without_invalid(&self) -> Self {
        let keep: Vec<usize> = (0..self.points.len())
            .filter(|&i| self.is_valid(i))
            .collect();
        fn pick<T: Copy>(v: &Option<Vec<T>>, keep: &[usize]) -> Option<Vec<T>> {
            v.as_ref().map(|v| keep.iter().map(|&i| v[i]).collect())
        }
        Self {
            layout: CloudLayout::Unorganized,
            points: keep.iter().map(|&i| self.points[i]).collect(),
            colors: pick(&self.colors, &keep),
            normals: pick(&self.normals, &keep),
            labels: pick(&self.labels, &keep),
            intensities: pick(&self.intensities, &keep),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn organised_cloud_addresses_grid() {
        let pts: Vec<_> = (0..6).map(|i| Point3::new(i as f32, 0.0, 1.0)).collect();
        let cloud = PointCloud::organized(3, 2, pts).unwrap();
        assert_eq!(cloud.at(1, 1).unwrap().x, 4.0);
        assert!(cloud.at(3, 0).is_none());
        assert_eq!(cloud.grid(), Some((3, 2)));
    }

    #[test]
    fn attribute_length_is_checked() {
        let cloud = PointCloud::unorganized(vec![Point3::origin(); 3]);
        assert!(cloud.clone().with_colors(vec![[0; 3]; 2]).is_err());
        assert!(cloud.with_labels(vec![1; 3]).is_ok());
        assert!(PointCloud::organized(2, 2, vec![Point3::origin(); 3]).is_err());
    }

    #[test]
    fn invalid_points_are_dropped_with_their_attributes() {
        let nan = Point3::new(f32::NAN, f32::NAN, f32::NAN);
        let cloud = PointCloud::organized(
            3,
            1,
            vec![Point3::new(1.0, 2.0, 3.0), nan, Point3::origin()],
        )
        .unwrap()
        .with_colors(vec![[1, 1, 1], [2, 2, 2], [3, 3, 3]])
        .unwrap();
        assert_eq!(cloud.valid_count(), 2);
        let dense = cloud.without_invalid();
        assert_eq!(dense.len(), 2);
        assert_eq!(dense.colors().unwrap(), &[[1, 1, 1], [3, 3, 3]]);
        assert_eq!(dense.layout(), CloudLayout::Unorganized);
    }
}
