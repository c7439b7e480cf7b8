// The shared flattened scene, as `src/layout/mod.rs` and `src/transport/camera.rs` lay it out.
// Every struct here has a Rust twin of the same name and fields; `tests/layout.rs` compares
// sizes and offsets with naga's reflection of this file.

struct Triangle {
    v0: vec3<f32>,
    material: u32,
    v1: vec3<f32>,
    emitter: u32,
    v2: vec3<f32>,
    // The index in frame.planar_mirrors of the planar mirror this triangle is part of, or
    // NO_PLANAR_MIRROR.
    planar_mirror: u32,
    n: vec3<f32>,
    pad1: u32,
}

struct Sphere {
    center: vec3<f32>,
    radius: f32,
    material: u32,
    emitter: u32,
    flip: u32,
    pad0: u32,
}

struct Material {
    color: vec3<f32>,
    kind: u32,
    emission: vec3<f32>,
    ior: f32,
}

struct Emitter {
    prim: u32,
    area: f32,
    cdf: f32,
    pmf: f32,
}

// A four-wide BVH node: the children's boxes, one row per plane. Per child slot c: count[c] > 0
// is a leaf of count[c] entries of `prims` from child[c]; count[c] == 0 is the interior node
// child[c]; count[c] == EMPTY_SLOT is an unused slot.
struct BvhNode {
    min_x: vec4<f32>,
    max_x: vec4<f32>,
    min_y: vec4<f32>,
    max_y: vec4<f32>,
    min_z: vec4<f32>,
    max_z: vec4<f32>,
    child: vec4<u32>,
    count: vec4<u32>,
}

const EMPTY_SLOT: u32 = 0xffffffffu;

struct Camera {
    eye: vec3<f32>,
    width: u32,
    forward: vec3<f32>,
    height: u32,
    right: vec3<f32>,
    pad0: u32,
    up: vec3<f32>,
    pad1: u32,
}

// A planar mirror (planar_mirror.wgsl): the plane n . p = d of a set of mirror triangles of one
// material, their bounds, and how far from the plane a vertex of theirs may lie.
struct PlanarMirror {
    n: vec3<f32>,
    d: f32,
    lo: vec3<f32>,
    tolerance: f32,
    hi: vec3<f32>,
    material: u32,
}

const MAX_PLANAR_MIRRORS: u32 = 4u;

// One dispatch: which pixels (a tile), which samples, and the test-only faults.
struct Frame {
    camera: Camera,
    seed: u32,
    first_sample: u32,
    sample_count: u32,
    num_emitters: u32,
    tile_origin: vec2<u32>,
    tile_size: vec2<u32>,
    max_bounces: u32,
    specular_scale: f32,
    // Shadow rays per diffuse vertex (`--light-samples`).
    light_samples: u32,
    // Test-only: grey the light gathered after the first diffuse bounce (`Faults`), 0 or 1.
    grey_indirect: u32,
    // METHOD_PATH, METHOD_LIGHT, METHOD_BDPT, METHOD_SPPM, METHOD_VCM, METHOD_VCM_FULL,
    // METHOD_WHITTED, METHOD_PHOTON_MAP or METHOD_RADIOSITY.
    method: u32,
    // N: light subpaths per iteration (one per pixel).
    n_light_paths: u32,
    // The iteration's slot in the pass (its image sum and light-vertex counter).
    slot: u32,
    // Light vertices the pool holds.
    vertex_capacity: u32,
    // The light subpaths of this light-pass dispatch: path_origin .. path_origin + path_count.
    path_origin: u32,
    path_count: u32,
    // Test-only: splats with an importance that lacks one cos theta (`Faults`), 0 or 1.
    importance_missing_cos: u32,
    // tau of BDPT's Russian roulette on visibility rays (0: none).
    shadow_threshold: f32,
    // Merging's MIS constants this iteration (`MergeMis`; 0 but for SPPM and VCM).
    merge_vm: f32,
    merge_vc: f32,
    // The merge kernel's normalisation 1 / (pi r^2 N).
    merge_normalization: f32,
    // The film band: its first row and rows (pass sums; splat tallies and camera radiance).
    film_row: u32,
    film_rows: u32,
    // Pixels the band buffers hold.
    band_pixels: u32,
    // The first light subpath of the wave (the pool's path heads are the wave's).
    wave_origin: u32,
    // Test-only: a subpath goes on past a hit whose density vanishes (`Faults`), 0 or 1.
    continue_at_vanishing_density: u32,
    // tau of VCM's Russian roulette on merge queries (0 but for vcm and vcm-full).
    merge_rr_threshold: f32,
    // Test-only: merge queries rouletted but not divided by their probability, 0 or 1.
    merge_rr_undivided: u32,
    // How many of planar_mirrors the scene has.
    planar_mirror_count: u32,
    // Whether the camera subpaths go on past their first diffuse vertex (`MergeMis`), 0 or 1:
    // 1 but for SPPM and vcm that merges.
    camera_goes_on: u32,
    // The iteration's merge radius r_i (0 but for SPPM and VCM).
    merge_radius: f32,
    // Whether merges use each camera vertex's radius within its clearance (vcm, 1) or r_i
    // everywhere (0), and the least share of r_i it leaves (`merging::CLEARANCE_FLOOR`).
    merges_within_clearance: u32,
    clearance_floor: f32,
    // The view's reach: a camera vertex this far from the eye or farther merges within
    // merge_radius, a nearer one within its share (`merging::footprint_share`; 0: all within it).
    merge_reach: f32,
    // SAMPLER_INDEPENDENT or SAMPLER_SOBOL (`--sampler`, sampling.wgsl).
    sampler: u32,
    // Adaptive sampling (path tracing): the dispatch covers pixel_runs[run_offset..][..run_count]
    // instead of a tile of pixels (run_count 0: the tile, each pixel the frame's samples).
    run_offset: u32,
    run_count: u32,
    // To the 16-byte boundary of planar_mirrors.
    pad4: u32,
    // The scene's planar mirrors, for next-event estimation through them (BDPT).
    planar_mirrors: array<PlanarMirror, MAX_PLANAR_MIRRORS>,
}

const METHOD_PATH: u32 = 0u;
const METHOD_LIGHT: u32 = 1u;
const METHOD_BDPT: u32 = 2u;
const METHOD_SPPM: u32 = 3u;
const METHOD_VCM: u32 = 4u;
const METHOD_VCM_FULL: u32 = 5u;
const METHOD_WHITTED: u32 = 6u;
const METHOD_PHOTON_MAP: u32 = 7u;
const METHOD_RADIOSITY: u32 = 8u;

// The sums of one pass of samples of one pixel (folded into f64 on the host).
struct PixelSums {
    sum: vec3<f32>,
    n: f32,
    sum_sq: vec3<f32>,
    dropped: f32,
    // The finite samples of even index: their sum and count (`PixelStats::even_sum`).
    even_sum: vec3<f32>,
    even_n: f32,
}

const KIND_DIFFUSE: u32 = 0u;
const KIND_MIRROR: u32 = 1u;
const KIND_GLASS: u32 = 2u;
const KIND_EMITTER: u32 = 3u;
const NOT_AN_EMITTER: u32 = 0xffffffffu;
const PRIM_SPHERE_BIT: u32 = 0x80000000u;
// A `prims` entry that no leaf covers (all bits set, the sphere bit among them).
const PRIM_PADDING: u32 = 0xffffffffu;
// The largest f32: "no limit" for ray parameters (WGSL has no infinity literal).
const F32_MAX: f32 = 3.40282347e38;
// The smallest normal f32 (Rust's f32::MIN_POSITIVE).
const F32_MIN_POSITIVE: f32 = 1.17549435e-38;

// The scene arrays (bindings 0 to 5) are declared in bindings_storage.wgsl or
// bindings_uniform.wgsl; the host chooses one (`Residency::preferred` in src/gpu/limits.rs).
@group(0) @binding(6) var<uniform> frame: Frame;
@group(0) @binding(7) var<storage, read_write> pixel_sums: array<PixelSums>;
// Adaptive sampling's runs of the pass (`PixelRun`): a pixel's index, its first sample and how
// many, and a word unused; read where frame.run_count is not 0.
@group(0) @binding(8) var<storage, read> pixel_runs: array<vec4<u32>>;
