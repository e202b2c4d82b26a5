//! The scheme options shared by the subcommands: a built-in by name, or a scheme file.

use std::path::{Path, PathBuf};

use subdiv::Mesh;
use subdiv::schemes::{Builtin, CurveScheme, Scheme};

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
}

/// The scheme in the file at `path`: a curve scheme if it reads as one, else a surface scheme
/// (TOML, or RON when the name ends in `.ron`).
pub(crate) fn read_any_scheme_file(path: &Path) -> Result<SchemeFile, UserError> {
    if !path.extension().is_some_and(|e| e.eq_ignore_ascii_case("ron")) {
        let text = std::fs::read_to_string(path).map_err(|e| UserError(format!("{}: {e}", path.display())))?;
        if let Ok(curve) = CurveScheme::from_toml_str(&text) {
            return Ok(SchemeFile::Curve(curve));
        }
    }
    read_scheme_file(path).map(|scheme| SchemeFile::Surface(Box::new(scheme)))
}

/// The user-defined surface scheme in the file at `path`: TOML, or RON when the name ends in
/// `.ron`.
pub(crate) fn read_scheme_file(path: &Path) -> Result<Scheme, UserError> {
    let text = std::fs::read_to_string(path).map_err(|e| UserError(format!("{}: {e}", path.display())))?;
    let parsed = if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("ron")) {
        Scheme::from_ron_str(&text)
    } else {
        Scheme::from_toml_str(&text)
    };
    parsed.map_err(|e| UserError(format!("{}: {e}", path.display())))
}

/// Whether `mesh`'s face-varying channels (texture coordinates) are left out under `scheme`,
/// which has no rules for them (the face-varying rules are those of the primal schemes with
/// crease rules): said, not silent, by every command that drops them.
pub(crate) fn channels_dropped(mesh: &Mesh, scheme: &Scheme) -> bool {
    !mesh.channels().is_empty() && !scheme.has_crease_rules()
}

/// What the commands say when [`channels_dropped`].
pub(crate) const CHANNELS_DROPPED: &str = "texture coordinates left out (the scheme has no face-varying rules)";

pub(crate) fn parse_builtin(name: &str) -> Result<Builtin, String> {
    Builtin::from_name(name).ok_or_else(|| {
        let known: Vec<_> = Builtin::ALL.iter().map(|s| s.name()).collect();
        format!("unknown scheme {name:?}; known: {}", known.join(", "))
    })
}

/// Arguments of `subdiv scheme`.
#[derive(Debug, clap::Args)]
pub(crate) struct PrintArgs {
    /// The built-in scheme to print.
    #[arg(value_parser = parse_builtin)]
    name: Builtin,
    /// Print RON instead of TOML.
    #[arg(long)]
    ron: bool,
}

/// `subdiv scheme NAME [--ron]`: a built-in scheme as a file, a template for one's own.
pub(crate) fn print(args: &PrintArgs, out: &mut impl std::io::Write) -> Result<(), UserError> {
    if args.ron {
        writeln!(out, "{}", args.name.scheme().to_ron_string())?;
    } else {
        write!(out, "{}", args.name.toml())?;
    }
    Ok(())
}
