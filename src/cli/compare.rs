//! `hexray compare`: a render against a reference, with thresholds for CI.

use super::*;
use anyhow::{Context, Result};
use clap::Args;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Args, Debug, Clone)]
pub(crate) struct CompareArgs {
    /// The render to judge (.exr or .npy).
    pub(crate) candidate: PathBuf,
    /// The reference (.exr or .npy).
    pub(crate) reference: PathBuf,
    /// The candidate's variance of the mean (default: CANDIDATE's NAME_var.exr when it exists).
    #[arg(long)]
    pub(crate) var: Option<PathBuf>,
    /// The reference's variance of the mean (default: REFERENCE's NAME_var.exr / NAME_var.npy
    /// when it exists).
    #[arg(long)]
    pub(crate) ref_var: Option<PathBuf>,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub(crate) json: bool,
    /// Exit with status 1 when the relMSE is above this (for CI).
    #[arg(long, value_parser = parse_threshold)]
    pub(crate) max_relmse: Option<f64>,
    /// Exit with status 1 when the share of pixel-channels beyond 5 standard errors is above
    /// this (for CI; needs both variances).
    #[arg(long, value_parser = parse_threshold)]
    pub(crate) max_px5: Option<f64>,
}

pub(crate) fn parse_threshold(s: &str) -> std::result::Result<f64, String> {
    match s.parse::<f64>() {
        Ok(x) if x.is_finite() && x >= 0.0 => Ok(x),
        _ => Err(format!("expected a number >= 0, found {s:?}")),
    }
}

/// NAME_var.EXT beside NAME.EXT, if that file exists.
pub(crate) fn variance_beside(path: &std::path::Path) -> Option<PathBuf> {
    let stem = path.file_stem()?.to_string_lossy();
    let ext = path.extension()?.to_string_lossy();
    let v = path.with_file_name(format!("{stem}_var.{ext}"));
    v.exists().then_some(v)
}

pub(crate) fn compare(args: &CompareArgs) -> ExitCode {
    let read = |p: &PathBuf| hexray::analysis::compare::read_image(p);
    let var = args
        .var
        .clone()
        .or_else(|| variance_beside(&args.candidate));
    let ref_var = args
        .ref_var
        .clone()
        .or_else(|| variance_beside(&args.reference));
    let mut notes = Vec::new();
    notes.extend(hexray::analysis::compare::scene_note(
        &args.candidate,
        &args.reference,
    ));
    let result = (|| -> Result<_> {
        if let Some(v) = &var {
            hexray::analysis::compare::check_variance_pair(&args.candidate, v)?;
        }
        if let Some(v) = &ref_var {
            hexray::analysis::compare::check_variance_pair(&args.reference, v)?;
        }
        let mut c = read(&args.candidate)?;
        let r = read(&args.reference)?;
        let mut vars = match (&var, &ref_var) {
            (Some(a), Some(b)) => Some((read(a)?, read(b)?)),
            _ => None,
        };
        // A render at k times the reference's size: each k x k block is one reference pixel.
        if let Some(k) = hexray::analysis::compare::block_factor(&c, &r) {
            c = hexray::analysis::compare::block_mean(&c, k, false);
            if let Some((vc, _)) = vars.as_mut() {
                *vc = hexray::analysis::compare::block_mean(vc, k, true);
            }
            notes.push(format!(
                "the candidate is {k}x the reference's size: compared as the means of its \
                 {k}x{k} blocks"
            ));
        }
        hexray::analysis::compare::compare(&c, &r, vars.as_ref().map(|(a, b)| (a, b))).with_context(
            || {
                format!(
                    "comparing {} with {}",
                    args.candidate.display(),
                    args.reference.display()
                )
            },
        )
    })();
    match result {
        Ok(mut cmp) => {
            cmp.notes.append(&mut notes);
            cmp.notes.extend(
                [
                    ("candidate", &args.candidate),
                    ("reference", &args.reference),
                ]
                .iter()
                .filter_map(|(what, path)| hexray::analysis::compare::consistency_note(what, path)),
            );
            if args.json {
                println!("{}", serde_json::to_string(&cmp).unwrap());
            } else {
                print!("{}", cmp.text());
            }
            // --max-relmse / --max-px5: the exit status a CI job can act on.
            let mut failed = false;
            if let Some(max) = args.max_relmse {
                // NaN counts as above.
                if cmp.relmse.is_nan() || cmp.relmse > max {
                    eprintln!(
                        "compare: relMSE {:e} is above --max-relmse {max:e}",
                        cmp.relmse
                    );
                    failed = true;
                }
            }
            if let Some(max) = args.max_px5 {
                match cmp.beyond_5_se {
                    Some(share) if share <= max => {}
                    Some(share) => {
                        eprintln!(
                            "compare: {share:e} of pixel-channels beyond 5 s.e., above --max-px5 \
                             {max:e}"
                        );
                        failed = true;
                    }
                    None => {
                        eprintln!(
                            "compare: --max-px5 needs both variances (NAME_var.exr beside each \
                             image, or --var and --ref-var)"
                        );
                        return ExitCode::from(EXIT_BAD_INPUT);
                    }
                }
            }
            if failed {
                ExitCode::FAILURE
            } else {
                ExitCode::SUCCESS
            }
        }
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(EXIT_BAD_INPUT)
        }
    }
}
