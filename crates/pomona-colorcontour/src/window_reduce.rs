//! Every cell of a grid combined with the cells of its square window, separably: along rows,
//! then down columns, each cell is combined with the cells `1..=radius` either side of it that
//! lie inside the grid (cells outside are ignored, not padded), one shifted slice at a time so
//! that the compiler can vectorise it. The cost grows with the radius, which is a few cells
//! where it is used: the mask closing ([`crate::close_mask`], `|` then `&`), the local maxima
//! of the Hough votes and of the distance transform ([`crate::local_maxima`], the larger), the
//! Hough votes' 3×3 sums (`+`) and the cells near a hypothesis whose votes the second pass
//! keeps (`|`).
//!
//! The operation must be commutative and associative over the values it meets (or, and, the
//! larger of totally ordered values, sums of integers), since each cell meets its neighbours in
//! no fixed order.

/// `values` (row-major, `width` wide, whole rows) with every cell replaced by `op` folded over
/// its `(2 radius + 1)²` window inside the grid.
pub(crate) fn window_reduce<T: Copy>(
    values: &[T],
    width: usize,
    radius: usize,
    op: impl Fn(T, T) -> T,
) -> Vec<T> {
    let mut across = values.to_vec();
    if width == 0 {
        return across;
    }
    for (out, row) in across
        .chunks_exact_mut(width)
        .zip(values.chunks_exact(width))
    {
        for shift in 1..=radius.min(width - 1) {
            for (o, &r) in out[..width - shift].iter_mut().zip(&row[shift..]) {
                *o = op(*o, r);
            }
            for (o, &r) in out[shift..].iter_mut().zip(&row[..width - shift]) {
                *o = op(*o, r);
            }
        }
    }
    let mut window = across.clone();
    let n = values.len();
    for shift in 1..=radius.min((n / width).saturating_sub(1)) {
        let offset = shift * width;
        for (o, &r) in window[..n - offset].iter_mut().zip(&across[offset..]) {
            *o = op(*o, r);
        }
        for (o, &r) in window[offset..].iter_mut().zip(&across[..n - offset]) {
            *o = op(*o, r);
        }
    }
    window
}
