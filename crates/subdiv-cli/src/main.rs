//! `subdiv`: inspect subdivision-surface control meshes (and, as the workspace grows, refine,
//! evaluate, tessellate and render them).
//!
//! Exit status: 0 on success (and when standard output is a pipe closed early, as by `head`),
//! 2 on bad input (unreadable or invalid mesh, bad arguments, an output that is an input) with
//! one line on stderr naming the file, the place and the rule; 130 / 143 on SIGINT / SIGTERM,
//! after removing the temporary file of any write in progress.

#![allow(clippy::print_stdout, clippy::print_stderr)]

mod analyze;
mod args;
mod eval;
mod info;
mod input;
mod merge;
mod plot;
mod refine;
mod render;
mod scheme_arg;
mod stencil;
mod tessellate;

use std::io::Write;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};

use clap::{Parser, Subcommand};

/// Exact, fast subdivision surfaces.
#[derive(Debug, Parser)]
#[command(name = "subdiv", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Print a mesh's topology (counts, face sizes, valences, boundaries, genus, tags) and every
    /// rule it breaks.
    Info(info::InfoArgs),
    /// Refine a mesh uniformly with any scheme (OpenSubdiv's rules for Catmull-Clark and Loop)
    /// and write it as OBJ.
    Refine(refine::RefineArgs),
    /// Reif's C1 test of a scheme at an extraordinary vertex: the spectrum of its derived local
    /// subdivision matrix and its characteristic map.
    Analyze(analyze::AnalyzeArgs),
    /// Print a built-in scheme's definition (TOML, or RON), a template for `--scheme-file`.
    Scheme(scheme_arg::PrintArgs),
    /// Exact limit stencils: a curve scheme's basis function and derivative on (1/n)ℤ, or a
    /// surface patch's position and tangent weights at rational (u, v).
    Stencil(stencil::StencilArgs),
    /// Exact limit positions and derivatives at face parameters (a grid on every face, or
    /// `face u v` samples), as CSV in OpenSubdiv's Bfr parameterization (osd_limit's columns).
    Eval(eval::EvalArgs),
    /// Plot a curve scheme's basis function φ (or φ′) on (1/n)ℤ as a PNG (paper 000, Figs. 2
    /// and 3).
    PlotBasis(plot::PlotArgs),
    /// Tessellate the limit surface so that every triangle lies within a tolerance of it
    /// (error-driven quadtree, watertight), written as GLB or OBJ.
    Tessellate(tessellate::TessellateArgs),
    /// Join the parts `tessellate --faces A..B` wrote (OBJ) into one mesh, welding the points
    /// their borders share (equal bit for bit): the whole tessellation, as one job would write it.
    Merge(merge::MergeArgs),
    /// Render the limit surface offscreen on the GPU to PNG: shaded with its exact normals,
    /// optionally with the tessellation's wireframe and the control cage, framed automatically;
    /// --frames renders an animation of a twisted cage.
    Render(render::RenderArgs),
}

/// A failure the user can act on: printed as one line, exit status 2.
#[derive(Debug)]
pub(crate) struct UserError(String);

impl<E: std::fmt::Display> From<E> for UserError {
    fn from(error: E) -> Self {
        Self(error.to_string())
    }
}

/// Set when standard output reports a closed pipe (`subdiv refine | head`): the reader wanted no
/// more, so the run ends quietly with exit status 0.
static PIPE_CLOSED: AtomicBool = AtomicBool::new(false);

/// Standard output, noting a closed pipe in [`PIPE_CLOSED`].
struct Stdout<W>(W);

impl<W: Write> Write for Stdout<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.0.write(buf).inspect_err(note_closed_pipe)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.0.flush().inspect_err(note_closed_pipe)
    }
}

fn note_closed_pipe(error: &std::io::Error) {
    if error.kind() == std::io::ErrorKind::BrokenPipe {
        PIPE_CLOSED.store(true, Ordering::Relaxed);
    }
}

/// On SIGINT or SIGTERM: delete the temporary file of any write in progress (the output keeps
/// its previous contents), then exit with 128 + the signal (130, 143), as shells expect.
fn remove_temporary_files_on_signals() {
    use signal_hook::consts::{SIGINT, SIGTERM};
    let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM]) else {
        // Without the handler the default action applies; the run itself is unaffected.
        return;
    };
    std::thread::spawn(move || {
        if let Some(signal) = signals.forever().next() {
            subdiv::io::remove_temporary_files();
            std::process::exit(128 + signal);
        }
    });
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    remove_temporary_files_on_signals();
    let stdout = std::io::stdout();
    let mut out = Stdout(stdout.lock());
    let result = match &cli.command {
        Command::Info(args) => info::run(args, &mut out),
        Command::Refine(args) => refine::run(args, &mut out),
        Command::Analyze(args) => analyze::run(args, &mut out),
        Command::Scheme(args) => scheme_arg::print(args, &mut out),
        Command::Stencil(args) => stencil::run(args, &mut out),
        Command::Eval(args) => eval::run(args, &mut out),
        Command::PlotBasis(args) => plot::run(args, &mut out),
        Command::Tessellate(args) => tessellate::run(args, &mut out),
        Command::Render(args) => render::run(args, &mut out),
        Command::Merge(args) => merge::run(args),
    };
    // A closed pipe (`subdiv info | head`) is not an error worth a message.
    let _ = out.flush();
    if PIPE_CLOSED.load(Ordering::Relaxed) {
        return ExitCode::SUCCESS;
    }
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(UserError(message)) => {
            let _ = writeln!(std::io::stderr(), "subdiv: {message}");
            ExitCode::from(2)
        }
    }
}
