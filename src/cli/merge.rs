//! `hexray merge`: renders of one scene with different seeds merged into one.

use super::*;
use anyhow::Result;
use clap::Args;
use hexray::film::output;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Args, Debug, Clone)]
pub(crate) struct MergeArgs {
    /// The parts: EXRs written by `hexray render --variance --seed S`, each with NAME_var.exr.
    #[arg(required = true)]
    pub(crate) parts: Vec<PathBuf>,
    /// The merged EXR; NAME.png and NAME_var.exr are written beside it.
    #[arg(short, long)]
    pub(crate) out: PathBuf,
    /// Exposure of the PNG in stops.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true, value_parser = parse_exposure)]
    pub(crate) exposure: f32,
    #[arg(long, short)]
    pub(crate) quiet: bool,
}

pub(crate) fn merge(args: &MergeArgs) -> Result<ExitCode> {
    if args.out.extension().is_none_or(|e| e != "exr") {
        eprintln!(
            "error: -o {}: the output must be an .exr path (the PNG is written beside it)",
            args.out.display()
        );
        return Ok(ExitCode::from(EXIT_BAD_INPUT));
    }
    let (exr, png, var) = output::output_paths(&args.out);
    for p in &args.parts {
        let same = |o: &PathBuf| std::fs::canonicalize(o).ok() == std::fs::canonicalize(p).ok();
        if [&exr, &var].into_iter().any(|o| o.exists() && same(o)) {
            eprintln!(
                "error: -o {} would overwrite the part {}; write the merge elsewhere",
                args.out.display(),
                p.display()
            );
            return Ok(ExitCode::from(EXIT_BAD_INPUT));
        }
    }
    // Every part is read and checked before anything is written.
    let parts = match args
        .parts
        .iter()
        .map(|p| hexray::film::parts::load_part(p))
        .collect::<Result<Vec<_>, _>>()
        .and_then(hexray::film::parts::merge)
    {
        Ok(m) => m,
        Err(e) => {
            eprintln!("error: {e}");
            return Ok(ExitCode::from(EXIT_BAD_INPUT));
        }
    };
    output::write_exr(&exr, &parts.mean, &parts.meta)?;
    output::write_png(&png, &parts.mean, args.exposure)?;
    let mut vmeta = parts.meta.clone();
    vmeta.set("content", "variance of the pixel mean");
    output::write_exr(&var, &parts.var, &vmeta)?;
    if !args.quiet {
        eprintln!(
            "merged {} parts (seeds {}) into {} spp: wrote {}, {} and {}",
            parts.meta.get("parts").unwrap_or("?"),
            parts.meta.get("seeds").unwrap_or("?"),
            parts.meta.get("spp").unwrap_or("?"),
            exr.display(),
            png.display(),
            var.display()
        );
    }
    Ok(ExitCode::SUCCESS)
}
