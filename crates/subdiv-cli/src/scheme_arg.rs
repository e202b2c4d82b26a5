//! The scheme options shared by the subcommands: a built-in by name, or a scheme file.

use std::path::{Path, PathBuf};

use subdiv::Surface;
use subdiv::schemes::{Builtin, CurveScheme, LocalCurveScheme, Scheme};

use crate::UserError;

/// `--scheme NAME` or `--scheme-file FILE`.
#[derive(Debug, clap::Args)]
pub(crate) struct SchemeArgs {
    /// Built-in subdivision scheme.
    #[arg(long, default_value = "catmull-clark", value_parser = parse_builtin)]
    scheme: Builtin,
    /// A user-defined scheme: a TOML file, or RON when the name ends in `.ron` (`subdiv scheme
    /// NAME` prints a built-in's file as a start). Overrides `--scheme`.
    #[arg(long, value_name = "FILE")]
    scheme_file: Option<PathBuf>,
}

impl SchemeArgs {
    /// The scheme asked for.
    pub(crate) fn resolve(&self) -> Result<Scheme, UserError> {
        match &self.scheme_file {
            Some(path) => read_scheme_file(path),
            None => Ok(self.scheme.scheme().clone()),
        }
    }
}

/// A user-defined scheme read from a file: a surface scheme, or a curve scheme (a TOML file with
/// `arity`, `offset` and `mask`, as `crates/subdiv-schemes/schemes/curves/` holds the built-ins).
pub(crate) enum SchemeFile {
    Surface(Box<Scheme>),
    Curve(CurveScheme),
    /// A curve scheme with rows of its own near the origin (TOML `[[rows]]`).
    LocalCurve(LocalCurveScheme),
}

/// The scheme in the file at `path` (TOML, or RON when the name ends in `.ron`): a curve scheme
/// if it reads as one (with `[[rows]]`: a local one), else a surface scheme.
pub(crate) fn read_any_scheme_file(path: &Path) -> Result<SchemeFile, UserError> {
    let (text, ron) = read_text(path)?;
    if !ron && text.lines().any(|l| l.trim() == "[[rows]]") {
        let local =
            LocalCurveScheme::from_toml_str(&text).map_err(|e| UserError(format!("{}: {e}", path.display())))?;
        return Ok(SchemeFile::LocalCurve(local));
    }
    let curve = if ron { CurveScheme::from_ron_str(&text) } else { CurveScheme::from_toml_str(&text) };
    match curve {
        Ok(curve) => Ok(SchemeFile::Curve(curve)),
        Err(_) => parse_surface(path, &text, ron).map(|scheme| SchemeFile::Surface(Box::new(scheme))),
    }
}

/// The user-defined surface scheme in the file at `path`: TOML, or RON when the name ends in
/// `.ron`.
pub(crate) fn read_scheme_file(path: &Path) -> Result<Scheme, UserError> {
    let (text, ron) = read_text(path)?;
    parse_surface(path, &text, ron)
}

/// The text of the scheme file at `path`, and whether it is RON (by its extension).
fn read_text(path: &Path) -> Result<(String, bool), UserError> {
    let text = std::fs::read_to_string(path).map_err(|e| UserError(format!("{}: {e}", path.display())))?;
    Ok((text, path.extension().is_some_and(|e| e.eq_ignore_ascii_case("ron"))))
}

/// `text`, the file at `path`, as a surface scheme.
fn parse_surface(path: &Path, text: &str, ron: bool) -> Result<Scheme, UserError> {
    let parsed = if ron { Scheme::from_ron_str(text) } else { Scheme::from_toml_str(text) };
    parsed.map_err(|e| UserError(format!("{}: {e}", path.display())))
}

/// Whether `surface`'s face-varying channels (texture coordinates) are left out: its scheme does
/// not take them in its face-varying mode ([`Surface::takes_channels`]). Said, not silent, by
/// every command that drops them.
pub(crate) fn channels_dropped(surface: &Surface) -> bool {
    !surface.mesh().channels().is_empty() && !surface.takes_channels()
}

/// What the commands say when [`channels_dropped`].
pub(crate) const CHANNELS_DROPPED: &str =
    "texture coordinates left out (the scheme has no face-varying rules but the linear ones, --fvar-interpolation all)";

pub(crate) fn parse_builtin(name: &str) -> Result<Builtin, String> {
    Builtin::from_name(name).ok_or_else(|| {
        let known: Vec<_> = Builtin::ALL.iter().map(|s| s.name()).collect();
        format!("unknown scheme {name:?}; known: {}", known.join(", "))
    })
}

/// Arguments of `subdiv scheme`.
#[derive(Debug, clap::Args)]
pub(crate) struct PrintArgs {
    /// The built-in scheme to print: a surface scheme, or a curve scheme (cubic-bspline,
    /// chaikin, four-point, six-point, sw-curve, nonuniform-cubic-bspline and its matrix-mask
    /// form nonuniform-cubic-bspline-matrix: TOML only).
    #[arg(value_parser = parse_any_builtin)]
    name: String,
    /// Print RON instead of TOML.
    #[arg(long)]
    ron: bool,
}

/// `subdiv scheme NAME [--ron]`: a built-in scheme as a file, a template for one's own.
pub(crate) fn print(args: &PrintArgs, out: &mut impl std::io::Write) -> Result<(), UserError> {
    match (Builtin::from_name(&args.name), CurveScheme::builtin_toml(&args.name)) {
        (Some(surface), _) if args.ron => writeln!(out, "{}", surface.scheme().to_ron_string())?,
        (Some(surface), _) => write!(out, "{}", surface.toml())?,
        (None, Some(_)) if args.ron => {
            let curve = CurveScheme::builtin(&args.name).expect("a built-in curve scheme");
            writeln!(out, "{}", curve.to_ron_string().map_err(|e| UserError(e.to_string()))?)?;
        }
        (None, Some(toml)) => write!(out, "{toml}")?,
        (None, None) => match LocalCurveScheme::builtin_toml(&args.name) {
            Some(_) if args.ron => {
                return Err(UserError(format!("{}: a local curve scheme is written in TOML only", args.name)));
            }
            Some(toml) => write!(out, "{toml}")?,
            None => return Err(UserError(parse_any_builtin(&args.name).unwrap_err())),
        },
    }
    Ok(())
}

/// A built-in surface or curve scheme's name.
fn parse_any_builtin(name: &str) -> Result<String, String> {
    if Builtin::from_name(name).is_some()
        || CurveScheme::builtin_toml(name).is_some()
        || LocalCurveScheme::builtin_toml(name).is_some()
    {
        return Ok(name.to_string());
    }
    let mut known: Vec<&str> = Builtin::ALL.iter().map(|s| s.name()).collect();
    known.extend(CurveScheme::BUILTIN_NAMES);
    known.extend(LocalCurveScheme::BUILTIN_NAMES);
    Err(format!("unknown scheme {name:?}; known: {}", known.join(", ")))
}
