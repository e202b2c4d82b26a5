//! The eigenbasis of one patch shape: its power-basis matrix if it is a polynomial patch, or
//! for an extraordinary shape the keeping child's eigen decomposition and the other
//! children's matrices into the regular polynomial (paper 002 §3).

use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock, PoisonError};

use faer::Mat;
use subdiv_mesh::{BoundaryInterpolation, DVec3, Patch};
use subdiv_schemes::{ChildDomain, PatchMatrices, PatchType, Scheme};

use crate::EvalError;
use crate::poly::PowerBasis;
use crate::surface::PatchSurface;

/// The largest valence eigenbases are built for.
pub const MAX_VALENCE: usize = 64;

/// Levels next to the extraordinary vertex evaluated by iterating the keeping child's matrix
/// (exact subdivision): after these, every component of modulus at most
/// [`KEPT_MODULUS`] — Jordan blocks included — has shrunk below `32·(4·0.07)^31 ≈ 2e−16` of its
/// start even in second derivatives (scaled by `4^level`), and far below in positions and first
/// derivatives, so the expansion in the kept eigenvectors is exact to rounding from here on.
pub const DIRECT_LEVELS: usize = 32;

/// Eigenvalues of modulus above this are kept in the expansion beyond [`DIRECT_LEVELS`]. Above
/// 1/16 on purpose: Loop at valence 3 has a Jordan block of eigenvalue 1/16 (the example
/// `spectrum` shows it), which the expansion could not hold.
pub const KEPT_MODULUS: f64 = 0.07;

/// Eigenvalues closer than this (relative) form one cluster, whose left and right eigenspaces
/// are paired as a whole.
const CLUSTER: f64 = 1e-7;

/// A complex number, as the expansion's per-point arithmetic needs it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Complex {
    pub(crate) re: f64,
    pub(crate) im: f64,
}

impl Complex {
    pub(crate) const ONE: Self = Self { re: 1.0, im: 0.0 };

    pub(crate) fn mul(self, o: Self) -> Self {
        Self { re: self.re * o.re - self.im * o.im, im: self.re * o.im + self.im * o.re }
    }

    /// `self^n` by squaring.
    pub(crate) fn pow(self, mut n: u32) -> Self {
        let (mut base, mut out) = (self, Self::ONE);
        while n > 0 {
            if n & 1 == 1 {
                out = out.mul(base);
            }
            base = base.mul(base);
            n >>= 1;
        }
        out
    }

    fn modulus(self) -> f64 {
        self.re.hypot(self.im)
    }
}

/// The spectrum of an extraordinary shape's keeping-child matrix `A`, and how well its kept
/// part is semisimple.
#[derive(Clone, Debug, PartialEq)]
pub struct EigenBasisSpectrum {
    /// All eigenvalues `(re, im)`, largest modulus first.
    pub eigenvalues: Vec<(f64, f64)>,
    /// How many (the first) are kept: modulus above [`KEPT_MODULUS`].
    pub kept: usize,
    /// The subdominant eigenvalue's modulus (the largest after 1).
    pub subdominant: f64,
    /// `max |A·x − λ·x|` over the kept right eigenvectors (unit length).
    pub right_residual: f64,
    /// `max |Y·X − I|`: the kept left eigenvectors against the right ones.
    pub biorthogonality: f64,
    /// `max |A^32 − X·Λ^32·Y| / max |A^32|`: how well the kept part alone reproduces `A` after
    /// [`DIRECT_LEVELS`] steps.
    pub reconstruction: f64,
    /// The condition number of the matrix of *all* right eigenvectors: near `1/ε` (or
    /// infinite) where `A` is defective somewhere, typically a Jordan block of eigenvalue 0.
    pub eigenvector_condition: f64,
}

/// One non-keeping child of an extraordinary shape: where it lies and its matrix into the
/// regular polynomial's coefficients.
#[derive(Clone, Debug)]
pub(crate) struct Child {
    pub(crate) domain: ChildDomain,
    /// `B · M_b`: power-basis coefficients of the child from the parent's control points,
    /// `n × K`, row-major.
    pub(crate) to_power: Vec<f64>,
    /// `B · M_b · x_i` for each kept eigenvector but the first (eigenvalue 1): `n × r`,
    /// row-major.
    pub(crate) modes: Vec<Complex>,
}

/// The extraordinary part of an [`EigenBasis`].
#[derive(Clone, Debug)]
pub(crate) struct Extraordinary {
    pub(crate) valence: usize,
    /// The keeping child's matrix `A`, `K × K`, row-major.
    pub(crate) a: Vec<f64>,
    /// The three non-keeping children.
    pub(crate) children: Vec<Child>,
    /// Child index for the code `(s ≥ ½) + 2·(t ≥ ½)` of a point scaled into the first ring.
    pub(crate) lookup: [u8; 4],
    /// The kept eigenvalues but the first (1).
    pub(crate) eigenvalues: Vec<Complex>,
    /// Their left eigenvectors, `r × K`, row-major, biorthogonal to the right ones.
    pub(crate) left: Vec<Complex>,
    /// The limit position's stencil (left eigenvector of 1, summing to 1).
    pub(crate) limit: Vec<f64>,
    /// Tangent-direction stencils at the vertex: the limits of the directions of `∂/∂s` along
    /// the first side and `∂/∂t` along the last.
    pub(crate) tangents: [Vec<f64>; 2],
    pub(crate) spectrum: EigenBasisSpectrum,
}

#[derive(Clone, Debug)]
pub(crate) enum Kind {
    /// A polynomial patch.
    Regular,
    /// An extraordinary one, with its regular children's polynomial.
    Extraordinary(Box<Extraordinary>),
}

/// What the eigenbasis evaluation of one patch shape needs, computed once per process (see
/// [`of`](Self::of)).
///
/// A *regular* shape (one whose children all have its shape) is a polynomial patch: the
/// power-basis matrix `B` (monomial coefficients from control points) is fitted to the scheme's
/// exact stencils and checked. An *extraordinary* shape (one whose child at corner 0 keeps it,
/// the other children being regular) gets the keeping child's matrix `A`, its kept eigenvalues
/// with left and right eigenvectors, and `B · M_b` for the three other children.
#[derive(Clone, Debug)]
pub struct EigenBasis {
    pub(crate) matrices: Arc<PatchMatrices>,
    pub(crate) shape: usize,
    pub(crate) power: PowerBasis,
    pub(crate) kind: Kind,
}

type CacheKey = (usize, usize);

/// An eigenbasis, or why the shape has none.
type Computed = Result<Arc<EigenBasis>, EvalError>;

impl EigenBasis {
    /// The eigenbasis of `shape` of `matrices`, computed once per process and shared (the
    /// cache holds the matrices, so their address identifies them).
    ///
    /// # Errors
    /// [`EvalError::NotEigenPatch`] for a shape that is neither polynomial nor extraordinary
    /// with polynomial children (boundary patches, interpolating schemes),
    /// [`EvalError::Valence`] beyond [`MAX_VALENCE`], [`EvalError::Eigen`] when the kept part
    /// of the spectrum is not semisimple or the subdominant eigenvalue is not a real pair.
    pub fn of(matrices: &Arc<PatchMatrices>, shape: usize) -> Result<Arc<Self>, EvalError> {
        // Refusals are kept too: a mesh asks for the same shape once per face, and a refusal
        // can come after the costly part (the auto route of a bilinear channel's surface asked
        // 52 times for eigenbases its spectrum refuses, fitting their children each time).
        static CACHE: OnceLock<Mutex<HashMap<CacheKey, Computed>>> = OnceLock::new();
        let key = (Arc::as_ptr(matrices) as usize, shape);
        let cache = CACHE.get_or_init(Mutex::default);
        if let Some(found) = cache.lock().unwrap_or_else(PoisonError::into_inner).get(&key) {
            return found.clone();
        }
        // Read or computed outside the lock; a race does it twice and keeps one, both equal.
        let computed = match crate::basis_table::committed(matrices, shape) {
            Some(read) => Ok(Arc::new(read)),
            None => Self::compute(matrices.clone(), shape).map(Arc::new),
        };
        cache.lock().unwrap_or_else(PoisonError::into_inner).entry(key).or_insert(computed).clone()
    }

    /// The eigenbasis of the interior patch of `scheme` whose corner 0 has `valence` (the
    /// scheme's regular valence gives the polynomial patch).
    ///
    /// # Errors
    /// [`EvalError::Valence`] outside `3..=`[`MAX_VALENCE`]; as [`PatchMatrices::of`] and
    /// [`of`](Self::of).
    pub fn interior(scheme: &Scheme, valence: usize) -> Result<Arc<Self>, EvalError> {
        if !(3..=MAX_VALENCE).contains(&valence) {
            return Err(EvalError::Valence { valence, max: MAX_VALENCE });
        }
        let matrices = PatchMatrices::of(scheme, PatchType::interior(valence), BoundaryInterpolation::EdgeOnly)?;
        Self::of(&matrices, 0)
    }

    /// The sub-patch matrices it was built from.
    pub fn matrices(&self) -> &Arc<PatchMatrices> {
        &self.matrices
    }

    /// The shape, an index into the matrices' shapes.
    pub fn shape(&self) -> usize {
        self.shape
    }

    /// The number of control points.
    pub fn size(&self) -> usize {
        self.matrices.shapes[self.shape].size
    }

    /// Whether the shape is a polynomial patch (no extraordinary vertex).
    pub fn is_regular(&self) -> bool {
        matches!(self.kind, Kind::Regular)
    }

    /// The extraordinary vertex's valence, `None` for a polynomial patch.
    pub fn valence(&self) -> Option<usize> {
        match &self.kind {
            Kind::Regular => None,
            Kind::Extraordinary(e) => Some(e.valence),
        }
    }

    /// The spectrum of the keeping child's matrix, `None` for a polynomial patch.
    pub fn spectrum(&self) -> Option<&EigenBasisSpectrum> {
        match &self.kind {
            Kind::Regular => None,
            Kind::Extraordinary(e) => Some(&e.spectrum),
        }
    }

    /// The surface over one patch with these control points (in [`subdiv_mesh::Patch`] order),
    /// with its per-face precomputation done.
    ///
    /// # Errors
    /// [`EvalError::ControlPoints`] when `points` does not have [`size`](Self::size) points.
    pub fn surface(self: &Arc<Self>, points: &[DVec3]) -> Result<PatchSurface, EvalError> {
        if points.len() != self.size() {
            return Err(EvalError::ControlPoints { expected: self.size(), given: points.len() });
        }
        Ok(PatchSurface::new(self.clone(), points))
    }

    pub(crate) fn compute(matrices: Arc<PatchMatrices>, shape: usize) -> Result<Self, EvalError> {
        let unsupported = |detail: &str| EvalError::NotEigenPatch {
            scheme: matrices.scheme.clone(),
            shape,
            patch: format!("{:?}", matrices.patch_type),
            detail: detail.to_string(),
        };
        let Some(this) = matrices.shapes.get(shape) else {
            return Err(unsupported("no such shape"));
        };
        // A derived configuration (semi-sharp features) has the stationary shapes of the types
        // among its own: they take the same routes, told by their signatures.
        let derived = matches!(matrices.patch_type, PatchType::Derived { .. });
        let corner = Patch::signature_vertices(&this.signature, this.size).next().unwrap_or_default();
        let (valence, sharp) = match matrices.patch_type {
            PatchType::Interior { valence, sharp } => (valence, !sharp.is_smooth()),
            PatchType::Derived { .. } => (corner.0 as usize, Patch::signature_has_sharp_features(&this.signature)),
            PatchType::Boundary { .. } => return Err(unsupported("boundary patches are evaluated by exact stencils")),
        };
        if derived && Patch::signature_vertices(&this.signature, this.size).any(|(_, boundary)| boundary) {
            return Err(unsupported("boundary patches are evaluated by exact stencils"));
        }
        if sharp {
            return Err(unsupported("patches with sharp features are evaluated by exact stencils"));
        }
        // Regular: every child has one shape whose children all have it (a B-spline patch
        // refines into B-spline patches); the fit then checks that the surface is polynomial.
        let closed = |r: usize| matrices.shapes[r].children.iter().all(|c| c.shape == r);
        let first = this.children.first().map_or(shape, |c| c.shape);
        if this.children.iter().all(|c| c.shape == first) && closed(first) {
            let power = PowerBasis::fit(&matrices, shape)?;
            return Ok(Self { matrices, shape, power, kind: Kind::Regular });
        }
        if shape != 0 && !derived {
            return Err(unsupported("only the extraordinary shape and polynomial shapes have an eigenbasis"));
        }
        if valence > MAX_VALENCE {
            return Err(EvalError::Valence { valence, max: MAX_VALENCE });
        }
        let Some((keep, a)) = matrices.keeping(shape) else {
            return Err(unsupported("no child keeps the shape"));
        };
        if keep != 0 {
            return Err(unsupported("the child that keeps the shape is not at corner 0"));
        }
        let others: Vec<_> = this.children.iter().enumerate().filter(|&(i, _)| i != keep).map(|(_, c)| c).collect();
        if others.len() != 3 {
            return Err(unsupported("the shape does not have three children besides the one at the vertex"));
        }
        let size = this.size;
        if size > crate::surface::MAX_PATCH {
            return Err(unsupported("the patch has more control points than Catmull-Clark's at valence 64"));
        }
        // The spectrum first: it refuses some schemes (bilinear), and costs less than the fits.
        let a_entries: Vec<f64> = (0..size).flat_map(|r| a.dense_row(r)).collect();
        let eigen_error = |detail: String| EvalError::Eigen { scheme: matrices.scheme.clone(), valence, detail };
        let decomposition = Decomposition::new(&a_entries, size).map_err(&eigen_error)?;
        // Each other child is a polynomial patch (its own shape: its control points hold the
        // extraordinary vertex at a different place); the fit checks that it is one.
        let powers = others.iter().map(|c| PowerBasis::fit(&matrices, c.shape)).collect::<Result<Vec<_>, _>>()?;

        let power = powers[0].clone();
        let n = power.kind.monomials();
        let children: Vec<Child> = others
            .iter()
            .zip(&powers)
            .map(|(c, child_power)| {
                let m: Vec<f64> = (0..c.rows()).flat_map(|r| c.dense_row(r)).collect();
                let to_power = child_power.compose(&m, size);
                let r = decomposition.eigenvalues.len();
                let mut modes = vec![Complex { re: 0.0, im: 0.0 }; n * r];
                for row in 0..n {
                    for i in 0..r {
                        let (mut re, mut im) = (0.0, 0.0);
                        for k in 0..size {
                            let w = to_power[row * size + k];
                            let x = decomposition.right[k * r + i];
                            re += w * x.re;
                            im += w * x.im;
                        }
                        modes[row * r + i] = Complex { re, im };
                    }
                }
                Child { domain: c.domain, to_power, modes }
            })
            .collect();
        let lookup = lookup_table(matrices.face_size, &children);
        let tangents = tangent_stencils(&power, &children, &lookup, &decomposition, size).map_err(eigen_error)?;
        let Decomposition { eigenvalues, left, limit, spectrum, .. } = decomposition;
        let extraordinary =
            Extraordinary { valence, a: a_entries, children, lookup, eigenvalues, left, limit, tangents, spectrum };
        Ok(Self { matrices, shape, power, kind: Kind::Extraordinary(Box::new(extraordinary)) })
    }
}

/// The child of each code `(s ≥ ½) + 2·(t ≥ ½)`, for a point of the first ring (outside the
/// keeping child, inside the parent): the child whose domain holds a point of that code.
fn lookup_table(face_size: usize, children: &[Child]) -> [u8; 4] {
    let representative: [(f64, f64); 4] = if face_size == 3 {
        [(0.3, 0.3), (0.6, 0.2), (0.2, 0.6), (0.5, 0.5)]
    } else {
        [(0.75, 0.25), (0.75, 0.25), (0.25, 0.75), (0.75, 0.75)]
    };
    let inside = |(u, v): (f64, f64)| {
        let e = 1e-12;
        u >= -e && v >= -e && if face_size == 3 { u + v <= 1.0 + e } else { u <= 1.0 + e && v <= 1.0 + e }
    };
    representative.map(|p| children.iter().position(|c| inside(c.domain.to_child(p.0, p.1))).unwrap_or(0) as u8)
}

/// The limits at the vertex of the directions of `∂/∂s` along the first side and `∂/∂t`
/// along the last, as stencils: near the vertex only the subdominant eigenvectors shape the
/// derivatives, so the direction at `(¾, 0)` of the subdominant part (`Σ x_i y_i`, the spectral
/// projector) is the limit direction.
fn tangent_stencils(
    power: &PowerBasis,
    children: &[Child],
    lookup: &[u8; 4],
    d: &Decomposition,
    size: usize,
) -> Result<[Vec<f64>; 2], String> {
    let r = d.eigenvalues.len();
    let sub = d.eigenvalues.first().map(|l| l.modulus()).ok_or("no subdominant eigenvalue")?;
    let pair: Vec<usize> = (0..r).filter(|&i| (d.eigenvalues[i].modulus() - sub).abs() <= CLUSTER * sub).collect();
    if pair.len() != 2 || pair.iter().any(|&i| d.eigenvalues[i].im.abs() > CLUSTER) {
        return Err(format!(
            "the subdominant eigenvalue is not a real double one ({:?}); tangent planes at the vertex need one",
            pair.iter().map(|&i| d.eigenvalues[i]).collect::<Vec<_>>()
        ));
    }
    let kind = power.kind;
    let directions = [(0.75, 0.0, 1usize), (0.0, 0.75, 2usize)].map(|(s, t, which)| {
        let child = &children[usize::from(lookup[if which == 1 { 1 } else { 2 }])];
        let (cu, cv) = child.domain.to_child(s, t);
        let m = crate::poly::monomial_row(kind, cu, cv, which);
        let mut stencil = vec![0.0; size];
        for &i in &pair {
            // ∂ of the polynomial B·M_b·x_i at the point, times y_i.
            let (mut re, mut im) = (0.0, 0.0);
            for (row, &w) in m.iter().enumerate() {
                let x = child.modes[row * r + i];
                re += w * x.re;
                im += w * x.im;
            }
            let factor = Complex { re, im };
            for (k, s) in stencil.iter_mut().enumerate() {
                *s += factor.mul(d.left[i * size + k]).re;
            }
        }
        stencil
    });
    Ok(directions)
}

/// The kept part of the eigen decomposition of `A`.
struct Decomposition {
    /// Kept eigenvalues but 1, largest modulus first.
    eigenvalues: Vec<Complex>,
    /// Their right eigenvectors, `K × r`, row-major.
    right: Vec<Complex>,
    /// Their left eigenvectors, `r × K`, row-major.
    left: Vec<Complex>,
    /// The left eigenvector of 1, summing to 1.
    limit: Vec<f64>,
    spectrum: EigenBasisSpectrum,
}

impl Decomposition {
    fn new(a: &[f64], size: usize) -> Result<Self, String> {
        let matrix = Mat::<f64>::from_fn(size, size, |r, c| a[r * size + c]);
        let right = matrix.eigen().map_err(|e| format!("eigen decomposition failed: {e:?}"))?;
        let left = matrix.transpose().to_owned().eigen().map_err(|e| format!("eigen decomposition failed: {e:?}"))?;
        let values = |e: &faer::linalg::solvers::Eigen<f64>| -> Vec<Complex> {
            e.S().column_vector().iter().map(|z| Complex { re: z.re, im: z.im }).collect()
        };
        let (rv, lv) = (values(&right), values(&left));
        let mut order: Vec<usize> = (0..size).collect();
        order.sort_by(|&i, &j| rv[j].modulus().total_cmp(&rv[i].modulus()).then(rv[j].re.total_cmp(&rv[i].re)));
        let eigenvalues_all: Vec<(f64, f64)> = order.iter().map(|&i| (rv[i].re, rv[i].im)).collect();
        let kept: Vec<usize> = order.iter().copied().filter(|&i| rv[i].modulus() > KEPT_MODULUS).collect();
        let column = |e: &faer::linalg::solvers::Eigen<f64>, i: usize| -> Vec<Complex> {
            let u = e.U();
            let v: Vec<Complex> = (0..size).map(|k| Complex { re: u[(k, i)].re, im: u[(k, i)].im }).collect();
            let norm = v.iter().map(|z| z.re * z.re + z.im * z.im).sum::<f64>().sqrt();
            v.into_iter().map(|z| Complex { re: z.re / norm, im: z.im / norm }).collect()
        };
        // Clusters of (numerically) equal kept eigenvalues; each pairs its right eigenvectors
        // with as many left ones.
        let close = |x: Complex, y: Complex| {
            Complex { re: x.re - y.re, im: x.im - y.im }.modulus() <= CLUSTER * x.modulus().max(1.0)
        };
        let mut done = vec![false; kept.len()];
        let mut values_out = Vec::new();
        let mut rights: Vec<Vec<Complex>> = Vec::new();
        let mut lefts: Vec<Vec<Complex>> = Vec::new();
        for (p, &i) in kept.iter().enumerate() {
            if done[p] {
                continue;
            }
            let members: Vec<usize> = (p..kept.len()).filter(|&q| !done[q] && close(rv[kept[q]], rv[i])).collect();
            members.iter().for_each(|&q| done[q] = true);
            let l_members: Vec<usize> = (0..size).filter(|&j| close(lv[j], rv[i])).collect();
            if l_members.len() != members.len() {
                return Err(format!(
                    "eigenvalue ({:.6}, {:.6}) has {} right and {} left eigenvectors: the kept part is not semisimple",
                    rv[i].re,
                    rv[i].im,
                    members.len(),
                    l_members.len()
                ));
            }
            let xs: Vec<Vec<Complex>> = members.iter().map(|&q| column(&right, kept[q])).collect();
            let ys: Vec<Vec<Complex>> = l_members.iter().map(|&j| column(&left, j)).collect();
            // G = Yᵀ X; the biorthogonal left eigenvectors are G⁻¹ Yᵀ.
            let m = members.len();
            let g: Vec<Complex> = (0..m * m)
                .map(|e| {
                    let (r, c) = (e / m, e % m);
                    dot(&ys[r], &xs[c])
                })
                .collect();
            let inverse = invert(&g, m).ok_or_else(|| {
                format!(
                    "eigenvalue ({:.6}, {:.6}): its left and right eigenvectors do not pair (a Jordan block): the kept \
                     part is not semisimple",
                    rv[i].re, rv[i].im
                )
            })?;
            for r in 0..m {
                let y: Vec<Complex> = (0..size)
                    .map(|k| {
                        let mut z = Complex { re: 0.0, im: 0.0 };
                        for c in 0..m {
                            let t = inverse[r * m + c].mul(ys[c][k]);
                            z.re += t.re;
                            z.im += t.im;
                        }
                        z
                    })
                    .collect();
                values_out.push(rv[kept[members[r]]]);
                rights.push(xs[r].clone());
                lefts.push(y);
            }
        }
        if values_out.is_empty() || !close(values_out[0], Complex::ONE) {
            return Err(format!("the dominant eigenvalue is {:?}, not 1", values_out.first()));
        }
        if values_out.len() > 1 && close(values_out[1], Complex::ONE) {
            return Err("eigenvalue 1 is not simple".to_string());
        }
        let r_all = values_out.len();
        // Residuals: A x = λ x, Y X = I, and the kept part after DIRECT_LEVELS steps.
        let mut right_residual = 0.0f64;
        for (x, &l) in rights.iter().zip(&values_out) {
            for row in 0..size {
                let mut z = Complex { re: 0.0, im: 0.0 };
                for (k, xk) in x.iter().enumerate() {
                    z.re += a[row * size + k] * xk.re;
                    z.im += a[row * size + k] * xk.im;
                }
                let lx = l.mul(x[row]);
                right_residual = right_residual.max(Complex { re: z.re - lx.re, im: z.im - lx.im }.modulus());
            }
        }
        let mut biorthogonality = 0.0f64;
        for (i, y) in lefts.iter().enumerate() {
            for (j, x) in rights.iter().enumerate() {
                let z = dot(y, x);
                let target = if i == j { 1.0 } else { 0.0 };
                biorthogonality = biorthogonality.max(Complex { re: z.re - target, im: z.im }.modulus());
            }
        }
        let mut power = Mat::<f64>::identity(size, size);
        for _ in 0..DIRECT_LEVELS {
            power = &matrix * &power;
        }
        let scale = power.norm_max().max(f64::MIN_POSITIVE);
        let mut reconstruction = 0.0f64;
        let lambda_n: Vec<Complex> = values_out.iter().map(|l| l.pow(DIRECT_LEVELS as u32)).collect();
        for row in 0..size {
            for col in 0..size {
                let mut z = 0.0;
                for i in 0..r_all {
                    z += rights[i][row].mul(lambda_n[i]).mul(lefts[i][col]).re;
                }
                reconstruction = reconstruction.max((z - power[(row, col)]).abs() / scale);
            }
        }
        let all = Mat::<faer::c64>::from_fn(size, size, |r, c| right.U()[(r, c)]);
        let sv = all.singular_values().map_err(|e| format!("SVD failed: {e:?}"))?;
        let eigenvector_condition = sv.first().copied().unwrap_or(0.0) / sv.last().copied().unwrap_or(0.0);
        let spectrum = EigenBasisSpectrum {
            eigenvalues: eigenvalues_all,
            kept: r_all,
            subdominant: values_out.get(1).map_or(0.0, |l| l.modulus()),
            right_residual,
            biorthogonality,
            reconstruction,
            eigenvector_condition,
        };
        if right_residual > 1e-9 || biorthogonality > 1e-8 || reconstruction > 1e-9 {
            return Err(format!(
                "the kept part of the spectrum (modulus > {KEPT_MODULUS}) is not semisimple to working precision: \
                 |Ax − λx| = {right_residual:.1e}, |YX − I| = {biorthogonality:.1e}, |A^{DIRECT_LEVELS} − XΛY| = \
                 {reconstruction:.1e}"
            ));
        }
        // The limit stencil: the left eigenvector of 1, scaled so that its weights sum to 1
        // (the right one is constant, so y·x = 1 says the same up to that constant).
        let sum: Complex =
            lefts[0].iter().fold(Complex { re: 0.0, im: 0.0 }, |s, z| Complex { re: s.re + z.re, im: s.im + z.im });
        let limit: Vec<f64> = lefts[0]
            .iter()
            .map(|z| {
                let d = sum.re * sum.re + sum.im * sum.im;
                (z.re * sum.re + z.im * sum.im) / d
            })
            .collect();
        let r = r_all - 1;
        let right_rest: Vec<Complex> = (0..size).flat_map(|k| rights[1..].iter().map(move |x| x[k])).collect();
        debug_assert_eq!(right_rest.len(), size * r);
        Ok(Self {
            eigenvalues: values_out[1..].to_vec(),
            right: right_rest,
            left: lefts[1..].iter().flatten().copied().collect(),
            limit,
            spectrum,
        })
    }
}

/// `Σ a_k b_k` (no conjugation: left eigenvectors are transposes).
fn dot(a: &[Complex], b: &[Complex]) -> Complex {
    a.iter().zip(b).fold(Complex { re: 0.0, im: 0.0 }, |s, (x, y)| {
        let t = x.mul(*y);
        Complex { re: s.re + t.re, im: s.im + t.im }
    })
}

/// The inverse of a small complex matrix by Gauss-Jordan with partial pivoting; `None` when
/// it is singular to working precision.
fn invert(g: &[Complex], m: usize) -> Option<Vec<Complex>> {
    let mut a = g.to_vec();
    let mut inv: Vec<Complex> =
        (0..m * m).map(|e| if e / m == e % m { Complex::ONE } else { Complex { re: 0.0, im: 0.0 } }).collect();
    let scale = g.iter().map(|z| z.modulus()).fold(0.0, f64::max);
    for col in 0..m {
        let pivot = (col..m).max_by(|&i, &j| a[i * m + col].modulus().total_cmp(&a[j * m + col].modulus()))?;
        if a[pivot * m + col].modulus() <= 1e-8 * scale {
            return None;
        }
        for k in 0..m {
            a.swap(col * m + k, pivot * m + k);
            inv.swap(col * m + k, pivot * m + k);
        }
        let p = a[col * m + col];
        let d = p.re * p.re + p.im * p.im;
        let pinv = Complex { re: p.re / d, im: -p.im / d };
        for k in 0..m {
            a[col * m + k] = a[col * m + k].mul(pinv);
            inv[col * m + k] = inv[col * m + k].mul(pinv);
        }
        for row in (0..m).filter(|&r| r != col) {
            let f = a[row * m + col];
            for k in 0..m {
                let (x, y) = (f.mul(a[col * m + k]), f.mul(inv[col * m + k]));
                a[row * m + k] = Complex { re: a[row * m + k].re - x.re, im: a[row * m + k].im - x.im };
                inv[row * m + k] = Complex { re: inv[row * m + k].re - y.re, im: inv[row * m + k].im - y.im };
            }
        }
    }
    Some(inv)
}
