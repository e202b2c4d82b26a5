//! `subdiv plot-basis`: a curve scheme's basis function φ (or φ′) on (1/n)ℤ as a PNG, paper
//! 000's Figures 2 (four-point, n = 21) and 3 (its derivative, n = 31) for any curve scheme; a
//! surface scheme's regular basis function φ (or ∂φ/∂u) on (1/n)ℤ² as a heat map.

use std::fmt;
use std::io::Write;
use std::path::{Path, PathBuf};

use image::{ImageFormat, Rgb, RgbImage};
use subdiv::schemes::{Builtin, CurveScheme, Scheme};
use subdiv::stencil::curve::basis_grid;
use subdiv::stencil::surface_basis::{SurfaceBasisGrid, SurfaceMask};

use crate::UserError;
use crate::scheme_arg::SchemeFile;

/// Arguments of `subdiv plot-basis`.
#[derive(Debug, clap::Args)]
pub(crate) struct PlotArgs {
    /// A built-in curve scheme (cubic-bspline, chaikin, four-point, six-point, sw-curve) or
    /// surface scheme (catmull-clark, loop, doo-sabin, midedge, sqrt3, butterfly, kobbelt,
    /// sw-quad, bilinear).
    #[arg(long, required_unless_present = "scheme_file")]
    scheme: Option<String>,
    /// A user-defined scheme: a curve scheme's TOML file with `arity`, `offset` and `mask` (the
    /// built-ins' are in `crates/subdiv-schemes/schemes/curves/`), or a surface scheme's.
    /// Overrides `--scheme`.
    #[arg(long, value_name = "FILE")]
    scheme_file: Option<PathBuf>,
    /// The grid rate: samples at k/n over the support (surfaces: at (i/n, j/n), n at most 128).
    #[arg(long, default_value_t = 21, value_parser = clap::value_parser!(u32).range(1..=1024))]
    n: u32,
    /// Plot the derivative φ′ (surfaces: ∂φ/∂u) instead of φ.
    #[arg(long)]
    derivative: bool,
    /// The PNG to write (through a temporary file, then renamed).
    #[arg(short = 'o', long = "output", value_name = "OUT.png")]
    output: PathBuf,
    /// Image width in pixels.
    #[arg(long, default_value_t = 800, value_parser = clap::value_parser!(u32).range(64..=8192))]
    width: u32,
    /// Image height in pixels.
    #[arg(long, default_value_t = 500, value_parser = clap::value_parser!(u32).range(64..=8192))]
    height: u32,
}

/// Why `plot-basis` cannot plot the scheme asked for.
#[derive(Debug)]
enum PlotError {
    /// No built-in scheme has this name.
    Unknown(String),
    /// A local curve scheme: several basis functions near its special point.
    Local(String),
}

impl fmt::Display for PlotError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let curves = CurveScheme::BUILTIN_NAMES.join(", ");
        match self {
            Self::Unknown(name) => {
                let surfaces: Vec<&str> = Builtin::ALL.iter().map(|b| b.name()).collect();
                write!(f, "unknown scheme {name:?}; known: {curves}, {}", surfaces.join(", "))
            }
            Self::Local(name) => write!(
                f,
                "plot-basis draws uniform curve schemes ({curves}); `{name}` has rules of its own near the origin \
                 (`subdiv stencil --scheme-file` prints its basis functions)"
            ),
        }
    }
}

const WHITE: Rgb<u8> = Rgb([255, 255, 255]);
const AXIS: Rgb<u8> = Rgb([0, 0, 0]);
const ZERO: Rgb<u8> = Rgb([170, 170, 170]);
const LINE: Rgb<u8> = Rgb([40, 90, 200]);
const DOT: Rgb<u8> = Rgb([10, 20, 60]);

/// A small rasteriser: lines, dots and ticks on an RGB image, clipped to it.
struct Canvas {
    image: RgbImage,
}

impl Canvas {
    fn put(&mut self, x: i64, y: i64, colour: Rgb<u8>) {
        if let (Ok(x), Ok(y)) = (u32::try_from(x), u32::try_from(y))
            && x < self.image.width()
            && y < self.image.height()
        {
            self.image.put_pixel(x, y, colour);
        }
    }

    /// A line `width` pixels thick (Bresenham, with a square brush).
    fn line(&mut self, (x0, y0): (i64, i64), (x1, y1): (i64, i64), width: i64, colour: Rgb<u8>) {
        let (dx, dy) = ((x1 - x0).abs(), -(y1 - y0).abs());
        let (sx, sy) = (if x0 < x1 { 1 } else { -1 }, if y0 < y1 { 1 } else { -1 });
        let (mut x, mut y, mut err) = (x0, y0, dx + dy);
        let half = width / 2;
        loop {
            for i in -half..width - half {
                for j in -half..width - half {
                    self.put(x + i, y + j, colour);
                }
            }
            if x == x1 && y == y1 {
                break;
            }
            let e2 = 2 * err;
            if e2 >= dy {
                err += dy;
                x += sx;
            }
            if e2 <= dx {
                err += dx;
                y += sy;
            }
        }
    }

    /// A filled disc.
    fn dot(&mut self, (cx, cy): (i64, i64), radius: i64, colour: Rgb<u8>) {
        for i in -radius..=radius {
            for j in -radius..=radius {
                if i * i + j * j <= radius * radius {
                    self.put(cx + i, cy + j, colour);
                }
            }
        }
    }
}

/// A tick spacing of 1, 2 or 5 times a power of ten giving about `count` ticks over `span`.
fn tick_step(span: f64, count: f64) -> f64 {
    let raw = span / count;
    let power = 10f64.powf(raw.log10().floor());
    [1.0, 2.0, 5.0, 10.0].into_iter().map(|m| m * power).find(|&s| s >= raw).unwrap_or(10.0 * power)
}

/// Draws the samples `(x, y)` as a line through dots, with axes, ticks and the zero line.
fn plot(samples: &[(f64, f64)], width: u32, height: u32) -> RgbImage {
    let mut canvas = Canvas { image: RgbImage::from_pixel(width, height, WHITE) };
    let (w, h) = (i64::from(width), i64::from(height));
    let (left, right, top, bottom) = (w / 12, w - w / 24, h / 16, h - h / 10);
    let x_lo = samples.iter().map(|s| s.0).fold(f64::INFINITY, f64::min);
    let x_hi = samples.iter().map(|s| s.0).fold(f64::NEG_INFINITY, f64::max);
    let y_lo = samples.iter().map(|s| s.1).fold(0.0, f64::min);
    let y_hi = samples.iter().map(|s| s.1).fold(0.0, f64::max);
    let pad = 0.08 * (y_hi - y_lo).max(1e-12);
    let (y_lo, y_hi) = (y_lo - pad, y_hi + pad);
    let (x_lo, x_hi) = if x_hi > x_lo { (x_lo, x_hi) } else { (x_lo - 1.0, x_hi + 1.0) };
    let px = |x: f64| left + ((x - x_lo) / (x_hi - x_lo) * (right - left) as f64).round() as i64;
    let py = |y: f64| bottom - ((y - y_lo) / (y_hi - y_lo) * (bottom - top) as f64).round() as i64;

    // The zero line, then the axes (left and bottom) with ticks.
    canvas.line((left, py(0.0)), (right, py(0.0)), 1, ZERO);
    canvas.line((left, top), (left, bottom), 2, AXIS);
    canvas.line((left, bottom), (right, bottom), 2, AXIS);
    let tick = (h / 60).max(3);
    let step = tick_step(x_hi - x_lo, 8.0);
    let mut x = (x_lo / step).ceil() * step;
    while x <= x_hi + 1e-9 {
        canvas.line((px(x), bottom), (px(x), bottom + tick), 1, AXIS);
        x += step;
    }
    let step = tick_step(y_hi - y_lo, 6.0);
    let mut y = (y_lo / step).ceil() * step;
    while y <= y_hi + 1e-9 {
        canvas.line((left - tick, py(y)), (left, py(y)), 1, AXIS);
        y += step;
    }

    let points: Vec<(i64, i64)> = samples.iter().map(|&(x, y)| (px(x), py(y))).collect();
    let thick = (w / 400).max(2);
    for pair in points.windows(2) {
        canvas.line(pair[0], pair[1], thick, LINE);
    }
    for &p in &points {
        canvas.dot(p, thick + 1, DOT);
    }
    canvas.image
}

/// Encodes the PNG and writes it atomically ([`subdiv::io::write_atomic`]: `<name>.<hex>.tmp`, synced,
/// renamed), so a failure leaves `path` as it was.
pub(crate) fn write_png(path: &Path, image: &RgbImage) -> Result<(), UserError> {
    let mut bytes = std::io::Cursor::new(Vec::new());
    image.write_to(&mut bytes, ImageFormat::Png).map_err(|e| UserError(format!("{}: {e}", path.display())))?;
    subdiv::io::write_atomic(path, |writer| writer.write_all(bytes.get_ref()))?;
    Ok(())
}

/// `subdiv plot-basis --scheme S --n N [--derivative] -o OUT.png`.
pub(crate) fn run(args: &PlotArgs, out: &mut impl Write) -> Result<(), UserError> {
    let curve = match (&args.scheme_file, &args.scheme) {
        (Some(path), _) => match crate::scheme_arg::read_any_scheme_file(path)? {
            SchemeFile::Curve(curve) => curve,
            SchemeFile::Surface(scheme) => return run_surface(args, &scheme, out),
            SchemeFile::LocalCurve(local) => {
                return Err(UserError(PlotError::Local(local.name().to_string()).to_string()));
            }
        },
        (None, Some(name)) => match (CurveScheme::builtin(name), Builtin::from_name(name)) {
            (Some(curve), _) => curve,
            (None, Some(surface)) => return run_surface(args, surface.scheme(), out),
            (None, None) => return Err(UserError(PlotError::Unknown(name.clone()).to_string())),
        },
        (None, None) => return Err(UserError("give --scheme NAME or --scheme-file FILE".to_string())),
    };
    let grid = basis_grid(&curve, args.n)?;
    let values = if args.derivative { grid.dphi_f64() } else { grid.phi_f64() };
    let n = f64::from(args.n);
    let samples: Vec<(f64, f64)> =
        values.iter().enumerate().map(|(k, &y)| ((grid.first + k as i64) as f64 / n, y)).collect();
    write_png(&args.output, &plot(&samples, args.width, args.height))?;
    let what = if args.derivative { "φ′" } else { "φ" };
    writeln!(
        out,
        "{}: {what} of {} at {} points of (1/{})Z, {}×{} pixels",
        args.output.display(),
        curve.name(),
        samples.len(),
        args.n,
        args.width,
        args.height
    )?;
    Ok(())
}

/// A surface scheme's regular basis function (or its `u` derivative) on `(1/n)ℤ²`, from its
/// scaling relation (route 1), as a heat map over its support in the lattice's coordinates
/// (triangle schemes: along the grid lines (1, 0) and (0, 1); the dual splits' control point at
/// `(½, ½)`): red above zero, blue below, white at zero, the lattice's lines grey.
fn run_surface(args: &PlotArgs, scheme: &Scheme, out: &mut impl Write) -> Result<(), UserError> {
    let mask = SurfaceMask::of(scheme)?;
    let grid = SurfaceBasisGrid::new(&mask, args.n)?;
    let (lo, extent) = grid.bounds();
    let sample = |m: [i64; 2]| -> f64 {
        let value = if args.derivative { grid.du(m) } else { grid.value(m) };
        value.map_or(0.0, |v| v.to_f64())
    };
    let values: Vec<f64> = (0..extent[0] * extent[1])
        .map(|k| sample([lo[0] + (k % extent[0]) as i64, lo[1] + (k / extent[0]) as i64]))
        .collect();
    let image = heat_map(&values, lo, extent, args.n, args.width, args.height);
    write_png(&args.output, &image)?;
    let what = if args.derivative { "∂φ/∂u" } else { "φ" };
    writeln!(
        out,
        "{}: {what} of {} at {} points of (1/{})Z², {}×{} pixels",
        args.output.display(),
        scheme.name,
        values.len(),
        args.n,
        args.width,
        args.height
    )?;
    Ok(())
}

/// `values` on the numerators `lo..lo + extent` (row-major, `u` fastest) of `(1/rate)ℤ²`,
/// bilinear between samples, as colours: the largest modulus full red or blue.
fn heat_map(values: &[f64], lo: [i64; 2], extent: [usize; 2], rate: u32, width: u32, height: u32) -> RgbImage {
    let mut canvas = Canvas { image: RgbImage::from_pixel(width, height, WHITE) };
    let scale = values.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(1e-300);
    let n = f64::from(rate);
    let (x_lo, y_lo) = (lo[0] as f64 / n, lo[1] as f64 / n);
    let (x_span, y_span) = (((extent[0] - 1) as f64 / n).max(1e-9), ((extent[1] - 1) as f64 / n).max(1e-9));
    // One scale for both axes, centred, with a margin.
    let (w, h) = (f64::from(width), f64::from(height));
    let unit = (0.9 * w / x_span).min(0.9 * h / y_span);
    let (x0, y0) = ((w - unit * x_span) / 2.0, (h + unit * y_span) / 2.0);
    let at = |i: usize, j: usize| values[j * extent[0] + i];
    for py in 0..height {
        for px in 0..width {
            // Grid coordinates of the pixel's centre.
            let gx = ((f64::from(px) + 0.5 - x0) / unit) * n;
            let gy = ((y0 - f64::from(py) - 0.5) / unit) * n;
            if gx < 0.0 || gy < 0.0 || gx > (extent[0] - 1) as f64 || gy > (extent[1] - 1) as f64 {
                continue;
            }
            let (i, j) =
                ((gx as usize).min(extent[0].saturating_sub(2)), (gy as usize).min(extent[1].saturating_sub(2)));
            let (fx, fy) = (gx - i as f64, gy - j as f64);
            let (i1, j1) = ((i + 1).min(extent[0] - 1), (j + 1).min(extent[1] - 1));
            let v =
                (1.0 - fy) * ((1.0 - fx) * at(i, j) + fx * at(i1, j)) + fy * ((1.0 - fx) * at(i, j1) + fx * at(i1, j1));
            let t = (v / scale).clamp(-1.0, 1.0);
            let fade = (255.0 * (1.0 - t.abs())).round() as u8;
            let colour = if t >= 0.0 { Rgb([255, fade, fade]) } else { Rgb([fade, fade, 255]) };
            canvas.put(i64::from(px), i64::from(py), colour);
        }
    }
    // The lattice's lines, at integer coordinates.
    let (px, py) = (|x: f64| (x0 + (x - x_lo) * unit).round() as i64, |y: f64| (y0 - (y - y_lo) * unit).round() as i64);
    let (x_hi, y_hi) = (x_lo + x_span, y_lo + y_span);
    for x in (x_lo.ceil() as i64)..=(x_hi.floor() as i64) {
        canvas.line((px(x as f64), py(y_lo)), (px(x as f64), py(y_hi)), 1, ZERO);
    }
    for y in (y_lo.ceil() as i64)..=(y_hi.floor() as i64) {
        canvas.line((px(x_lo), py(y as f64)), (px(x_hi), py(y as f64)), 1, ZERO);
    }
    canvas.image
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_round_numbers() {
        assert_eq!(tick_step(6.0, 8.0), 1.0);
        assert_eq!(tick_step(1.2, 6.0), 0.2);
        assert_eq!(tick_step(0.03, 6.0), 0.005);
    }

    #[test]
    fn lines_reach_both_ends_and_clip() {
        let mut canvas = Canvas { image: RgbImage::from_pixel(10, 10, WHITE) };
        canvas.line((-5, 2), (9, 2), 1, AXIS);
        assert_eq!(canvas.image.get_pixel(0, 2), &AXIS);
        assert_eq!(canvas.image.get_pixel(9, 2), &AXIS);
        assert_eq!(canvas.image.get_pixel(5, 3), &WHITE);
    }
}
