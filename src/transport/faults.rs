//! Planted faults: test-only changes to the integrators of both backends, for showing that the
//! statistical tests reject a wrong renderer. A render of a user's always uses [`Faults::NONE`].

/// Test-only changes to the integrator, for showing that the statistical tests reject a wrong
/// renderer. The production path uses `Faults::NONE`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Faults {
    /// Multiplies the throughput at every mirror and glass bounce (1 when correct).
    pub specular_scale: f32,
    /// Ends every path after this many bounces (`u32::MAX` when correct: no maximum depth).
    pub max_bounces: u32,
    /// Replaces the light a path gathers after its first diffuse bounce by its grey (the mean
    /// of its three channels): a renderer whose indirect light, and so its shadows, lose colour
    /// (false when correct).
    pub grey_indirect: bool,
    /// Light tracing and BDPT: splats with a camera importance that lacks one cos θ factor,
    /// 1 / (A_pix cos²θ) (false when correct).
    pub importance_missing_cos: bool,
    /// SPPM and VCM: merges counted with the kernel of the 3-D ball, 1 / (4/3 π r³), instead
    /// of the disk's 1 / (π r²) (false when correct).
    pub merge_kernel_ball: bool,
    /// Light tracing, BDPT and the merging methods: a subpath goes on past a hit whose area
    /// density vanishes in f32 (`subpath::density_vanishes`) instead of ending there, and its
    /// MIS quantities become NaN (false when correct).
    pub continue_at_vanishing_density: bool,
    /// VCM: merge queries rouletted (`subpath::merge_survival`) but not divided by their
    /// survival probability (false when correct).
    pub merge_rr_undivided: bool,
    /// BDPT (the CPU): the light that reaches a diffuse vertex from a planar mirror is
    /// taken by next-event estimation through the mirror and also, with the weights of the
    /// other strategies, by those (the emission a camera subpath meets in the mirror, the
    /// light subpath's vertices from that diffuse vertex on): counted about twice (false when
    /// correct).
    pub mirror_light_twice: bool,
    /// vcm: merges within the iteration's radius everywhere, also where another surface is
    /// nearer than that (`merging::local_radius`): still consistent, but the room's edges come
    /// out darker at a given radius (false when correct).
    pub merge_ignores_clearance: bool,
    /// The merging methods (the CPU): with fewer light subpaths N than pixels, the kernel's
    /// normalisation, the splats and the MIS weights count one per pixel instead of N (false
    /// when correct).
    pub light_paths_counted_per_pixel: bool,
    /// Radiosity: each form-factor ray counts this share of 1 / R (1 when correct), so that
    /// the rows of a closed scene sum to it instead of 1.
    pub form_factor_scale: f32,
    /// Radiosity: form-factor rays leave their patch uniformly over the hemisphere instead of
    /// cosine-distributed, which breaks reciprocity A_i F_ij = A_j F_ji (false when correct).
    pub form_factor_uniform_directions: bool,
    /// Radiosity: a patch's indirect light also counts its neighbours' emission,
    /// ρ_i Σ_j F_ij L_j, so that direct light is counted twice with next-event estimation's
    /// (false when correct).
    pub indirect_with_direct: bool,
    /// Adaptive sampling: a round's samples weigh 1 instead of the round's budget over the
    /// pixel's count (`crate::render::adaptive`), so that the counts, decided from the
    /// pixel's own earlier samples, bias its mean (false when correct).
    pub adaptive_pooled: bool,
}

impl Faults {
    pub const NONE: Faults = Faults {
        specular_scale: 1.0,
        max_bounces: u32::MAX,
        grey_indirect: false,
        importance_missing_cos: false,
        merge_kernel_ball: false,
        continue_at_vanishing_density: false,
        merge_rr_undivided: false,
        mirror_light_twice: false,
        merge_ignores_clearance: false,
        light_paths_counted_per_pixel: false,
        form_factor_scale: 1.0,
        form_factor_uniform_directions: false,
        indirect_with_direct: false,
        adaptive_pooled: false,
    };
}

impl Default for Faults {
    fn default() -> Self {
        Faults::NONE
    }
}
