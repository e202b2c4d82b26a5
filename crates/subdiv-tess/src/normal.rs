//! Unit normals of cross products, at every scale.

use glam::DVec3;

/// `c` scaled to unit length, or zero for a zero `c`: glam's `normalize_or_zero` (the same
/// bits) where `|c|²` is a normal f64, and otherwise `c` first scaled by a power of two (exact)
/// so that it is. Cross products of tangents scale as the square of the model, so a model of
/// size 1e-90 has `|c|² ≈ 1e-360`, which underflows to 0 and made every normal zero.
///
/// ```
/// use subdiv_tess::unit_normal;
/// use glam::DVec3;
///
/// let tiny = DVec3::new(1e-180, 0.0, 1e-180);
/// // |tiny|² underflows to 0, so glam's `normalize_or_zero` gives zero; this does not.
/// assert!((unit_normal(tiny) - DVec3::new(1.0, 0.0, 1.0).normalize()).length() < 1e-15);
/// assert_eq!(unit_normal(DVec3::ZERO), DVec3::ZERO);
/// ```
pub fn unit_normal(c: DVec3) -> DVec3 {
    let n = c.normalize_or_zero();
    if n != DVec3::ZERO {
        return n;
    }
    // Only the cold path looks at the magnitude: this runs once per output vertex.
    let m = c.abs().max_element();
    if m == 0.0 || !m.is_finite() {
        return n;
    }
    // 2^-e with m = f · 2^e, f in [1, 2): the largest coordinate lands in [1, 2).
    let e = m.log2().floor() as i32;
    (c * 2f64.powi(-e.clamp(-1000, 1000))).normalize_or_zero()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normals_are_unit_from_1e_minus_160_to_1e150_and_equal_to_glams_between() {
        let direction = DVec3::new(0.3, -0.5, 0.8);
        for e in [-300, -200, -180, -100, 0, 100, 150, 300] {
            let c = direction * 10f64.powi(e);
            let n = unit_normal(c);
            assert!((n.length() - 1.0).abs() < 1e-15 && (n - direction.normalize()).length() < 1e-15, "1e{e}: {n}");
        }
        let c = DVec3::new(1.5, 2.0, -0.25);
        assert_eq!(unit_normal(c).to_array(), c.normalize_or_zero().to_array());
    }
}
