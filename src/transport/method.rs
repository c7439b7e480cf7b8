//! The light-transport methods a render can use.

use clap::ValueEnum;

/// Which estimator renders the image (`--method`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Method {
    /// Path tracing with next-event estimation and MIS (`src/cpu/path.rs`): one independent
    /// camera path per sample.
    Path,
    /// Light tracing (`src/cpu/light_path.rs`): light subpaths connected to the camera. Sees
    /// nothing through mirrors or glass: surfaces seen only that way stay black.
    Light,
    /// Bidirectional path tracing (`src/cpu/bdpt.rs`): every connection of a camera subpath and
    /// a light subpath, weighed by MIS, and next-event estimation through planar mirrors (the
    /// light's mirror image).
    Bdpt,
    /// Stochastic progressive photon mapping (`src/cpu/bdpt.rs` in its photon-mapping mode):
    /// each camera subpath follows mirrors and glass to its first diffuse vertex and gathers
    /// the photons (light vertices) of the iteration within a radius that shrinks over
    /// iterations. Consistent, not unbiased: the bias vanishes as the radius does.
    Sppm,
    /// Vertex connection and merging at the first diffuse vertex (`src/cpu/bdpt.rs` with
    /// merging): each camera subpath follows mirrors and glass to its first diffuse vertex and
    /// ends there after next-event estimation, a connection to each vertex of its light
    /// subpath and a merge with the iteration's photons, all weighed by MIS with light tracing
    /// over exactly those strategies (`crate::transport::subpath`). Consistent, not unbiased. With
    /// `--radius 0` it is bdpt.
    Vcm,
    /// Vertex connection and merging as published (Georgiev et al. 2012; `src/cpu/bdpt.rs`
    /// with merging): BDPT's strategies (next-event estimation through planar mirrors only with
    /// `--radius 0`, where it is bdpt) and photon merging at every diffuse camera vertex, all
    /// weighed by MIS. Consistent, not unbiased.
    VcmFull,
    /// Whitted ray tracing (`src/cpu/whitted.rs`): direct light at each diffuse surface the
    /// camera sees, and perfect reflection and refraction at mirrors and glass, both followed.
    /// Biased: it leaves out indirect diffuse light and caustics (light that reaches a diffuse
    /// surface by way of a mirror or glass).
    Whitted,
    /// Photon mapping in Jensen's two-pass form (`src/cpu/photon_map.rs`): a caustic map
    /// (photons that came by mirrors and glass alone) and a global map (photons after a diffuse
    /// scattering), traced anew each iteration; at the first diffuse point the camera sees,
    /// next-event estimation, the caustic map, and final gathering (one cosine-sampled ray to a
    /// diffuse point, where the direct light and both maps are taken). Biased: the fixed radius
    /// blurs the light (not progressive, so the bias does not shrink with samples).
    PhotonMap,
    /// Radiosity (`src/cpu/radiosity.rs`): the diffuse surfaces cut into patches, their form
    /// factors by ray casting and the radiosity equation solved once by Jacobi iterations;
    /// the image follows mirrors and glass as Whitted's to the first diffuse surface, takes
    /// direct light there by next-event estimation and the indirect light of the patch solution.
    /// Biased: the indirect light is constant over each patch, and it leaves out caustics and
    /// the indirect light that passes a mirror or glass.
    Radiosity,
}

impl Method {
    /// `hexray render`'s method when none is given: the one with the lowest relMSE at equal
    /// time on the three reference scenes on each backend (docs/methods.md, "The default
    /// method"), the GPU backend's judged on a hardware GPU: on an NVIDIA H200 at 256x256
    /// (6 s) vcm had 0.75 of path's relMSE by the geometric mean, vcm-full 0.91 and sppm 2.47
    /// (docs/journal/2026-11-27_h200.md); on lavapipe (30 s) vcm and sppm are level (0.126 and 0.123, one render
    /// each). Consistent, not unbiased: the summary line says so, and `hexray reference` keeps
    /// path tracing.
    pub const DEFAULT: Method = Method::Vcm;

    /// Samples (iterations) when neither `--spp` nor `--time` is given, so that the default
    /// render (tncg15_room, 512x512) takes about as long as path tracing's 64 samples: 64 of
    /// path tracing, of Whitted and of radiosity (whose samples cost less; radiosity's solve comes
    /// once, before them); 8 of the methods that trace a light subpath and a camera subpath per pixel
    /// and iteration, which cost 3-9x a path-traced sample (`hexray bench`; VCM's merges cost
    /// more as the image grows, since every pixel adds a photon; on 2 cores of an Intel Xeon VM,
    /// 64 spp of path took 6.28 s and 7 iterations of vcm 6.3 s).
    pub fn default_samples(self) -> u32 {
        match self {
            Method::Path | Method::Whitted | Method::Radiosity => 64,
            _ => 8,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Method::Path => "path",
            Method::Light => "light",
            Method::Bdpt => "bdpt",
            Method::Sppm => "sppm",
            Method::Vcm => "vcm",
            Method::VcmFull => "vcm-full",
            Method::Whitted => "whitted",
            Method::PhotonMap => "photon-map",
            Method::Radiosity => "radiosity",
        }
    }

    /// The method called `name` (as in the EXR metadata).
    pub fn from_name(name: &str) -> Option<Method> {
        Method::value_variants()
            .iter()
            .copied()
            .find(|m| m.name() == name)
    }

    /// The names of the methods with `property`, comma-separated, in `--method`'s order: for
    /// messages that name which methods an option is for.
    pub fn names_where(property: impl Fn(Method) -> bool) -> String {
        let names: Vec<&str> = Method::value_variants()
            .iter()
            .copied()
            .filter(|&m| property(m))
            .map(Method::name)
            .collect();
        names.join(", ")
    }

    /// Whether the method traces light subpaths that every pixel of an iteration may use
    /// (splatted or merged), so that an iteration's pixels share samples and its statistics
    /// are batch means (`crate::film::Film`).
    pub fn splats(self) -> bool {
        !matches!(self, Method::Path | Method::Whitted | Method::Radiosity)
    }

    /// The light the method leaves out by construction, a bias that no number of samples
    /// removes, for the summary line, the EXR metadata (`omits`) and `hexray compare`; None for
    /// the unbiased methods and the merging ones (whose bias shrinks with the radius).
    pub fn omits(self) -> Option<&'static str> {
        match self {
            Method::Whitted => Some(
                "indirect diffuse light and caustics (light that reaches a diffuse surface by way \
                 of a mirror or glass)",
            ),
            Method::Radiosity => Some(
                "caustics and indirect light by way of mirrors or glass, and the variation of \
                 indirect light within a patch (constant per patch, form factors from a finite \
                 number of rays)",
            ),
            _ => None,
        }
    }

    /// Whether the method merges photons (density estimation within a radius): biased by the
    /// radius, a bias that the film's standard error does not cover and that vanishes as the
    /// radius shrinks over iterations in the progressive ones (consistent, not unbiased).
    pub fn merges(self) -> bool {
        matches!(
            self,
            Method::Sppm | Method::Vcm | Method::VcmFull | Method::PhotonMap
        )
    }

    /// Whether the merge radius shrinks over iterations (α < 1), so that the bias vanishes
    /// (SPPM, VCM): every merging method but photon-map, whose radius is fixed.
    pub fn progressive(self) -> bool {
        self.merges() && self != Method::PhotonMap
    }

    /// Whether the method merges within each camera vertex's clearance
    /// (`merging::local_radius`): `vcm`, whose merges all happen at the first diffuse vertex of
    /// a camera subpath, so that a radius that depends on that vertex enters every MIS weight
    /// of a path alike (`subpath`, "A radius of the vertex").
    pub fn merges_within_clearance(self) -> bool {
        matches!(self, Method::Vcm)
    }

    /// Whether the method connects camera vertices to light vertices and emitters (BDPT's
    /// strategies).
    pub fn connects(self) -> bool {
        matches!(self, Method::Bdpt | Method::Vcm | Method::VcmFull)
    }
}

impl std::fmt::Display for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}
