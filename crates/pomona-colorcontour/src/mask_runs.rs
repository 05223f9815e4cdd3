//! Runs of mask pixels along rows and the 8-connected regions they form, for the mask stages
//! that label regions (the colour hysteresis, [`crate::hysteresis_mask`]; the contour stage,
//! [`crate::trace_contours`]). A region is labelled through its runs — a union–find over runs
//! that touch in consecutive rows — rather than pixel by pixel, so the cost grows with the
//! number of runs, not of pixels.

/// A run of pixels `x0..x1` of row `y`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Run {
    pub y: usize,
    pub x0: usize,
    pub x1: usize,
}

impl Run {
    /// Pixels in the run.
    pub fn len(&self) -> usize {
        self.x1 - self.x0
    }
}

/// The runs of the pixels passing a test, row by row.
pub(crate) struct Runs {
    pub runs: Vec<Run>,
    /// Row `y`'s runs are `runs[row_starts[y]..row_starts[y + 1]]`.
    row_starts: Vec<usize>,
}

impl Runs {
    /// The maximal runs of the pixels of `values` (row-major, `width` wide) that pass `test`,
    /// in raster order; none for a width of 0.
    pub fn passing<T: Copy>(values: &[T], width: usize, test: impl Fn(T) -> bool) -> Self {
        let [runs] = Self::by_level(values, width, |v| u8::from(test(v)));
        runs
    }

    /// The maximal runs of the `values` (row-major, `width` wide) at or above `high` and of
    /// those in `low..high`, in raster order, in one pass over the values: the same runs as
    /// [`Runs::passing`] with those two tests (the colour hysteresis reads both).
    pub fn strong_and_weak(values: &[u8], width: usize, (high, low): (u8, u8)) -> (Self, Self) {
        let [weak, strong] =
            Self::by_level(values, width, |v| u8::from(v >= low) + u8::from(v >= high));
        (strong, weak)
    }

    /// The maximal runs of each level 1..=N of the values (`level` gives 0..=N; 0 is no run),
    /// in raster order, in one pass: per row, each pixel's level, then the places where it
    /// changes as bits of 64-pixel words, visited by their trailing zeros — a branch per run
    /// end, not per pixel (a textured frame has many run ends).
    fn by_level<T: Copy, const N: usize>(
        values: &[T],
        width: usize,
        level: impl Fn(T) -> u8,
    ) -> [Self; N] {
        let mut out: [Self; N] = std::array::from_fn(|_| Self {
            runs: Vec::new(),
            row_starts: vec![0],
        });
        if width == 0 {
            return out;
        }
        let mut levels = vec![0u8; width];
        for (y, row) in values.chunks_exact(width).enumerate() {
            for (l, &v) in levels.iter_mut().zip(row) {
                *l = level(v);
            }
            let mut emit = |kind: u8, x0: usize, x1: usize| {
                if let Some(runs) = usize::from(kind)
                    .checked_sub(1)
                    .and_then(|k| out.get_mut(k))
                {
                    runs.runs.push(Run { y, x0, x1 });
                }
            };
            let (mut kind, mut x0) = (levels[0], 0);
            for first in (1..width).step_by(64) {
                let last = (first + 64).min(width);
                let mut changes = 0u64;
                for (bit, (a, b)) in levels[first..last]
                    .iter()
                    .zip(&levels[first - 1..last - 1])
                    .enumerate()
                {
                    changes |= u64::from(a != b) << bit;
                }
                while changes != 0 {
                    let x = first + changes.trailing_zeros() as usize;
                    changes &= changes - 1;
                    emit(kind, x0, x);
                    (kind, x0) = (levels[x], x);
                }
            }
            emit(kind, x0, width);
            for runs in &mut out {
                runs.row_starts.push(runs.runs.len());
            }
        }
        out
    }

    /// Rows of the image.
    pub fn rows(&self) -> usize {
        self.row_starts.len() - 1
    }

    /// Row `y`'s runs with their indices.
    pub fn row(&self, y: usize) -> (usize, &[Run]) {
        let (a, b) = (self.row_starts[y], self.row_starts[y + 1]);
        (a, &self.runs[a..b])
    }

    /// Pixels in each region of `sets` (this image's [`Runs::regions`]), indexed by the
    /// region's root run (0 for runs that are not roots).
    pub fn region_areas(&self, sets: &mut DisjointSets) -> Vec<usize> {
        let mut area = vec![0usize; self.runs.len()];
        for (k, run) in self.runs.iter().enumerate() {
            area[sets.find(k)] += run.len();
        }
        area
    }

    /// The 8-connected regions: runs of consecutive rows that touch are one region.
    pub fn regions(&self) -> DisjointSets {
        let mut sets = DisjointSets::new(self.runs.len());
        for y in 1..self.rows() {
            touching(self.row(y - 1), self.row(y), |a, b| sets.union(a, b));
        }
        sets
    }
}

/// Calls `f(index in a, index in b)` for every pair of runs of `a` and `b` (each sorted by
/// `x0`, of one row) that touch 8-connectedly when their rows are adjacent or the same: they
/// overlap or meet at a corner (and, in one row, two runs of different kinds meet end to end).
pub(crate) fn touching(
    (first_a, a): (usize, &[Run]),
    (first_b, b): (usize, &[Run]),
    mut f: impl FnMut(usize, usize),
) {
    let (mut i, mut j) = (0, 0);
    while i < a.len() && j < b.len() {
        if a[i].x0 <= b[j].x1 && b[j].x0 <= a[i].x1 {
            f(first_a + i, first_b + j);
        }
        if a[i].x1 < b[j].x1 {
            i += 1;
        } else {
            j += 1;
        }
    }
}

/// Union–find over run indices (path halving; a set's root is its smallest index, so the root
/// of a region is its first run in raster order).
pub(crate) struct DisjointSets {
    parent: Vec<usize>,
}

impl DisjointSets {
    /// `n` sets of one run each.
    pub fn new(n: usize) -> Self {
        Self {
            parent: (0..n).collect(),
        }
    }

    /// The root of `i`'s set.
    pub fn find(&mut self, mut i: usize) -> usize {
        while self.parent[i] != i {
            self.parent[i] = self.parent[self.parent[i]];
            i = self.parent[i];
        }
        i
    }

    /// Joins the sets of `a` and `b`.
    pub fn union(&mut self, a: usize, b: usize) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            self.parent[ra.max(rb)] = ra.min(rb);
        }
    }
}
