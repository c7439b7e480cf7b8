//! What an image of a bidirectional method says of the choices behind it, for the EXR metadata
//! and the log: BDPT's τ and specular camera subpaths, the merging methods' radius schedule.

/// BDPT's choices for a render's provenance: τ of the Russian roulette on visibility rays, and
/// how many pixels trace several camera subpaths per iteration.
pub fn bidirectional_provenance(
    shadow_threshold: f32,
    specular_camera_subpaths: u32,
    specular_pixels: usize,
) -> Vec<(&'static str, String)> {
    vec![
        ("shadow_rr_threshold", format!("{shadow_threshold:e}")),
        (
            "specular_camera_subpaths",
            format!("{specular_camera_subpaths} in {specular_pixels} pixels"),
        ),
    ]
}

/// The merging methods' radius for a render's provenance: the largest r_1 (scene units), α,
/// and the view's reach at which a camera vertex takes r_1 ("uniform" where every vertex does).
pub fn merging_provenance(
    radius: &crate::transport::merging::MergeRadius,
) -> Vec<(&'static str, String)> {
    vec![
        ("merge_radius", format!("{:e}", radius.initial)),
        ("merge_alpha", format!("{}", radius.alpha)),
        (
            "merge_reach",
            if radius.reach > 0.0 {
                format!("{:e}", radius.reach)
            } else {
                "uniform".to_string()
            },
        ),
    ]
}

/// Radiosity's settings and solve for a render's provenance: the patch size, the form-factor
/// rays per patch, the patches, the Jacobi steps (and whether they converged) and the seconds
/// of the form factors and of the rest of the solve.
pub fn radiosity_provenance(
    settings: crate::transport::patches::RadiositySettings,
    patches: usize,
    steps: u32,
    converged: bool,
    seconds: (f64, f64),
) -> Vec<(&'static str, String)> {
    vec![
        ("patch_size", format!("{}", settings.patch_size)),
        ("patch_rays", settings.patch_rays.to_string()),
        ("patches", patches.to_string()),
        (
            "jacobi_steps",
            format!("{steps}{}", if converged { "" } else { " (not converged)" }),
        ),
        (
            "radiosity_solve_seconds",
            format!(
                "{:.3} (form factors {:.3}, Jacobi and indirect light {:.3})",
                seconds.0 + seconds.1,
                seconds.0,
                seconds.1
            ),
        ),
    ]
}
