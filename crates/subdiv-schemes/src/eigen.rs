//! Eigenvalues of the derived local matrices (surfaces and curves share one solver and one
//! order).

/// The eigenvalues of the `size × size` matrix with entries `get(row, column)`, as `(re, im)`,
/// largest modulus first (ties: larger real part first); `Err` carries the solver's message.
pub(crate) fn eigenvalues(size: usize, get: impl Fn(usize, usize) -> f64) -> Result<Vec<(f64, f64)>, String> {
    let matrix = faer::Mat::<f64>::from_fn(size, size, get);
    let mut values: Vec<(f64, f64)> =
        matrix.eigenvalues().map_err(|e| format!("{e:?}"))?.iter().map(|z| (z.re, z.im)).collect();
    sort_by_modulus(&mut values);
    Ok(values)
}

/// Largest modulus first; ties: larger real part first.
pub(crate) fn sort_by_modulus(values: &mut [(f64, f64)]) {
    values.sort_by(|a, b| {
        let (ma, mb) = (a.0.hypot(a.1), b.0.hypot(b.1));
        mb.total_cmp(&ma).then(b.0.total_cmp(&a.0))
    });
}
