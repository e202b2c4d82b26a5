//! `cargo xtask osd-refine`: our uniform refinement against OpenSubdiv's on the shared corpus
//! (levels 1 to 3), through `subdiv_testkit::opensubdiv`.

use std::path::Path;

pub(crate) fn run(osd_refine: &Path, meshes: &Path, levels: &[usize]) -> Result<(), String> {
    let report = subdiv_testkit::opensubdiv::compare_refinement(osd_refine, meshes, levels)?;
    println!(
        "osd-refine: {} mesh-levels equal to 1e-12 x bbox, {} differ, {} skipped",
        report.equal,
        report.differ.len(),
        report.skipped.len()
    );
    for line in report.differ.iter().chain(&report.skipped) {
        println!("  {line}");
    }
    if report.differ.is_empty() { Ok(()) } else { Err(format!("{} mesh-levels differ", report.differ.len())) }
}
