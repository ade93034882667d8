//! A piecewise-constant 2-D distribution (pbrt-v4's `PiecewiseConstant2D`)
//! as one array of CDFs: the marginal over rows, then each row's
//! conditional over its columns. Built here in f64 and stored in f32, the
//! form `sample_environment` and `environment_pdf` read
//! (shaders/lights.wgsl): a cell's probability is read from its CDF's
//! step, so sampling and pdf agree, to the bit, on what each cell gets.

/// The CDFs of `values` (`rows` × `columns`, row-major, each ≥ 0): the
/// marginal (rows + 1 entries), then row r's conditional at
/// rows + 1 + r·(columns + 1). A row (or the whole) with no weight is
/// uniform, as in pbrt.
pub fn cdf_2d(values: &[f64], rows: usize, columns: usize) -> Vec<f32> {
    debug_assert_eq!(values.len(), rows * columns);
    let row_sums: Vec<f64> = values.chunks(columns).map(|r| r.iter().sum()).collect();
    let mut cdf = cdf_1d(&row_sums);
    for row in values.chunks(columns) {
        cdf.extend(cdf_1d(row));
    }
    cdf
}

/// The CDF of `values` (n + 1 entries from 0 to 1), uniform where they sum
/// to 0. Rounded once to f32 from f64 sums: non-decreasing, and exactly 1
/// at the end.
fn cdf_1d(values: &[f64]) -> Vec<f32> {
    let total: f64 = values.iter().sum();
    let n = values.len();
    let mut cdf = Vec::with_capacity(n + 1);
    let mut sum = 0.0;
    cdf.push(0.0);
    for (i, v) in values.iter().enumerate() {
        sum += v;
        let c = if total > 0.0 {
            sum / total
        } else {
            (i + 1) as f64 / n as f64
        };
        cdf.push(c as f32);
    }
    cdf[n] = 1.0;
    cdf
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_and_columns_follow_their_weights() {
        let cdf = cdf_2d(&[1.0, 3.0, 0.0, 0.0, 2.0, 2.0], 3, 2);
        // Marginal: rows weigh 4, 0, 4.
        assert_eq!(cdf[..4], [0.0, 0.5, 0.5, 1.0]);
        // Row 0: 1 and 3; row 1 (no weight): uniform; row 2: 2 and 2.
        assert_eq!(cdf[4..], [0.0, 0.25, 1.0, 0.0, 0.5, 1.0, 0.0, 0.5, 1.0]);
    }
}
