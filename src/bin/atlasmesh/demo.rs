//! `atlasmesh demo`: the whole method on built-in synthetic data.

use crate::summary::print_summary;
use crate::terminal::Terminal;
use anyhow::Context;
use clap::Args;
use std::path::PathBuf;

/// Arguments of `atlasmesh demo`.
#[derive(Args)]
pub struct DemoArgs {
    /// Output folder.
    #[arg(long, default_value = "atlasmesh-demo")]
    out: PathBuf,
}

/// Runs `atlasmesh demo`: the 2D demo in OUT, the 3D demo in OUT/3d.
pub fn run(a: DemoArgs, term: &Terminal) -> anyhow::Result<()> {
    let out = a.out;
    let r = atlasmesh::study::demo(&out, term).context("demo")?;
    println!("2D (outlines, quadrilaterals):");
    print_summary(&r, &out);
    let out3 = out.join("3d");
    let r3 = atlasmesh::study::demo_3d(&out3, term).context("3D demo")?;
    println!("3D (surfaces, hexahedra):");
    print_summary(&r3, &out3);
    println!("meshes (VTU) and plots (PNG) in {}", out.display());
    println!("2D report: {}", out.join("report.html").display());
    println!("3D report: {}", out3.join("report.html").display());
    Ok(())
}
