// What the bidirectional methods share: `src/transport/subpath.rs`, line for line. The stored light
// vertex and Georgiev et al.'s recursive MIS quantities (power heuristic, beta = 2, without Russian
// roulette's survival probabilities; src/transport/subpath.rs says why).

// A vertex of a light subpath on a non-specular surface, stored for the camera subpaths.
struct LightVertex {
    p: vec3<f32>,
    // The largest coordinate of the point's error bound.
    p_err: f32,
    // Unit geometric normal, turned to the side the light arrived from.
    n: vec3<f32>,
    material: u32,
    // Unit direction back toward the previous light vertex.
    wo: vec3<f32>,
    // Edges from the light point.
    length: u32,
    // alpha: Le / p_A times f |cos| / pdf of every scattering since.
    throughput: vec3<f32>,
    // The next vertex of the same light subpath in the pool, or NO_VERTEX.
    next: u32,
    d_vcm: f32,
    d_vc: f32,
    d_vm: f32,
    // The light subpath's index (its pixel).
    path: u32,
}

const NO_VERTEX: u32 = 0xffffffffu;

// What a merge reads of a light vertex, in the hash grid's entry order (subpath.rs:
// PhotonRecord, the same layout): the normal, the length, alpha, and the light side's part of the
// merge weight's denominator at the iteration's radius, or d_vm where merges are not weighed.
struct PhotonRecord {
    n: vec3<f32>,
    length: u32,
    throughput: vec3<f32>,
    w_light: f32,
}

// The bounce from which BDPT's and VCM's light subpaths are rouletted (src/transport/subpath.rs
// says why it is earlier than the path tracer's RR_START_BOUNCE).
const LIGHT_SUBPATH_RR_START_BOUNCE: u32 = 1u;

// The light pass's stored vertices (a pool shared by the light subpaths of one wave, each
// subpath a list through `next`), the order-independent tallies (splat.wgsl), and each pixel's
// camera-subpath radiance of the iteration, waiting for the resolve pass.
@group(1) @binding(0) var<storage, read_write> light_vertices: array<LightVertex>;
@group(1) @binding(1) var<storage, read_write> tallies: array<atomic<u32>>;
@group(1) @binding(2) var<storage, read_write> camera_radiance: array<vec4<f32>>;

// Russian roulette on a visibility ray by the contribution it would bring: traced with
// probability min(1, max channel / tau) (`shadow_survival`).
fn shadow_survival(contribution: vec3<f32>, threshold: f32) -> f32 {
    let c = max_element(contribution);
    if c >= threshold || threshold <= 0.0 {
        return 1.0;
    }
    return c / threshold;
}

// The exponent of the power heuristic, applied to each density ratio.
fn mis(x: f32) -> f32 {
    return x * x;
}

// Merging's constants in the weights (`MergeMis`): vm = eta^beta, vc = eta^-beta with
// eta = pi r^2 N; both 0 without merging (BDPT), which leaves BDPT's weights exactly.
struct MergeMis {
    vm: f32,
    vc: f32,
    camera_goes_on: bool,
}

// This iteration's merging constants (both 0 but for SPPM and VCM).
fn iteration_merge() -> MergeMis {
    return MergeMis(frame.merge_vm, frame.merge_vc, frame.camera_goes_on != 0u);
}

// The constants for a merge within share times the iteration's radius (`MergeMis::within`).
fn merge_within(merge: MergeMis, share: f32) -> MergeMis {
    let s = mis(share * share);
    return MergeMis(merge.vm * s, merge.vc / s, merge.camera_goes_on);
}

// Whether the method takes BDPT's strategies and weighs every strategy against them
// (Method::connects: BDPT, VCM, vcm-full; not SPPM or photon-map).
fn connects() -> bool {
    return frame.method == METHOD_BDPT || frame.method == METHOD_VCM || frame.method == METHOD_VCM_FULL;
}

// Whether this iteration merges photons (SPPM, VCM, photon-map, at a radius above 0).
fn merges() -> bool {
    return (frame.method == METHOD_SPPM || frame.method == METHOD_VCM || frame.method == METHOD_VCM_FULL || frame.method == METHOD_PHOTON_MAP) && frame.merge_normalization > 0.0;
}

// Georgiev's recursive quantities of one subpath vertex (`SubpathMis`).
struct SubpathMis {
    d_vcm: f32,
    d_vc: f32,
    d_vm: f32,
}

// At the camera: its direction density (the importance W, times the pixel's n_c camera
// subpaths), N light subpaths competing for the pixel through t = 1.
fn mis_camera(n_light_paths: f32, pdf_camera: f32) -> SubpathMis {
    return SubpathMis(mis(n_light_paths / pdf_camera), 0.0, 0.0);
}

// At the light point: its area density, the direction's density and the emitter's cosine.
fn mis_light(pdf_area: f32, pdf_dir: f32, cos: f32, merge: MergeMis) -> SubpathMis {
    let emission_pdf = pdf_area * pdf_dir;
    let d_vc = mis(cos / emission_pdf);
    return SubpathMis(mis(pdf_area / emission_pdf), d_vc, d_vc * merge.vc);
}

// Whether a hit's area density vanishes in f32 (mis(cos) below the smallest normal f32, |cos| <
// 1.1e-19): the subpath ends there, since mis_at_hit would divide by it (subpath.rs explains why
// that changes no estimate). Written so that a NaN cosine ends it too.
fn density_vanishes(cos: f32) -> bool {
    return !(mis(cos) >= F32_MIN_POSITIVE);
}

// At a hit dist2 (squared) away, |cos| at the surface: solid angle becomes area. The caller has
// ended the subpath where that density vanishes.
fn mis_at_hit(m: SubpathMis, dist2: f32, cos: f32) -> SubpathMis {
    var r = m;
    r.d_vcm *= mis(dist2);
    r.d_vcm /= mis(cos);
    r.d_vc /= mis(cos);
    r.d_vm /= mis(cos);
    return r;
}

// After sampling a direction at a non-specular vertex: density pdf, cosine cos_out, and the
// reverse density pdf_rev of the arriving direction; with merging, the merge here too.
fn mis_after_diffuse(m: SubpathMis, cos_out: f32, pdf: f32, pdf_rev: f32, merge: MergeMis) -> SubpathMis {
    var r = m;
    let ratio = mis(cos_out / pdf);
    r.d_vc = ratio * (m.d_vc * mis(pdf_rev) + m.d_vcm + merge.vm);
    r.d_vm = ratio * (m.d_vm * mis(pdf_rev) + m.d_vcm * merge.vc + 1.0);
    r.d_vcm = mis(1.0 / pdf);
    return r;
}

// After a specular bounce: no connection here; the equal Dirac densities cancel.
fn mis_after_specular(m: SubpathMis, cos_out: f32) -> SubpathMis {
    var r = m;
    r.d_vcm = 0.0;
    r.d_vc *= mis(cos_out);
    r.d_vm *= mis(cos_out);
    return r;
}

// s = 0: the camera subpath finds an emitter.
fn weight_emission(camera: SubpathMis, pdf_area: f32, pdf_dir: f32) -> f32 {
    let others = mis(pdf_area) * camera.d_vcm + mis(pdf_area * pdf_dir) * camera.d_vc;
    return 1.0 / (1.0 + others);
}

// s = 1: next-event estimation from a camera vertex.
fn weight_next_event(camera: SubpathMis, merge: MergeMis, pdf_bsdf: f32, pdf_light: f32, pdf_emit: f32, pdf_rev: f32) -> f32 {
    // The camera subpath that goes on from the vertex and hits the emitter.
    var w_light = 0.0;
    if merge.camera_goes_on {
        w_light = mis(pdf_bsdf / pdf_light);
    }
    let w_camera = mis(pdf_emit) * (camera.d_vcm + camera.d_vc * mis(pdf_rev) + merge.vm);
    return 1.0 / (w_light + 1.0 + w_camera);
}

// s >= 2, t >= 2: a camera vertex connected to a stored light vertex.
fn weight_connection(camera: SubpathMis, light: SubpathMis, merge: MergeMis, camera_to_light: f32, camera_rev: f32, light_to_camera: f32, light_rev: f32) -> f32 {
    // The camera subpath that goes on from the camera vertex to the light vertex and beyond.
    var w_light = 0.0;
    if merge.camera_goes_on {
        w_light = mis(camera_to_light) * (light.d_vcm + light.d_vc * mis(light_rev) + merge.vm);
    }
    let w_camera = mis(light_to_camera) * (camera.d_vcm + camera.d_vc * mis(camera_rev) + merge.vm);
    return 1.0 / (w_light + 1.0 + w_camera);
}

// t = 1: a light vertex connected to the camera.
fn weight_to_camera(light: SubpathMis, merge: MergeMis, pdf_camera: f32, n_light_paths: f32, light_rev: f32) -> f32 {
    // The camera subpaths that take the vertex as their first and connect (d_vcm) or merge
    // (vm) there, and those that go on from it (d_vc).
    var beyond = 0.0;
    if merge.camera_goes_on {
        beyond = light.d_vc * mis(light_rev);
    }
    let w_light = mis(pdf_camera / n_light_paths) * (light.d_vcm + beyond + merge.vm);
    return 1.0 / (w_light + 1.0);
}

// s = 1, t = 1: the light point itself seen by the camera.
fn weight_light_point_to_camera(pdf_camera: f32, n_light_paths: f32, pdf_area: f32) -> f32 {
    return 1.0 / (1.0 + mis(pdf_camera / (n_light_paths * pdf_area)));
}

// Merging a photon (light vertex) at a camera vertex is weighed against the connection at the
// light vertex and every strategy earlier on either subpath (subpath.rs: weight_merge):
// 1 / (light side + 1 + camera side). The camera pass adds the two sides below itself, the
// camera side once per query.

// The light side's part of weight_merge's denominator, which does not depend on the camera
// vertex (the CPU computes it once per photon: cpu/bdpt.rs, PhotonRecord).
fn merge_light_share(light: SubpathMis, merge: MergeMis, camera_to_light: f32) -> f32 {
    // The connection at the camera vertex (d_vcm), and the strategies whose camera subpath
    // goes on to the photon's previous vertex and beyond (d_vm).
    var beyond = 0.0;
    if merge.camera_goes_on {
        beyond = light.d_vm * mis(camera_to_light);
    }
    return light.d_vcm * merge.vc + beyond;
}

// The record of light vertex v in this iteration (PhotonRecord::new): merge_light_share with
// the photon's cos theta / pi toward its previous vertex where the method weighs its merges
// (VCM), else the vertex's d_vm.
fn photon_record(v: LightVertex) -> PhotonRecord {
    var w_light = v.d_vm;
    if connects() {
        let light_mis = SubpathMis(v.d_vcm, v.d_vc, v.d_vm);
        let cos_light = dot(v.n, v.wo);
        w_light = merge_light_share(light_mis, iteration_merge(), cos_light * FRAC_1_PI);
    }
    return PhotonRecord(v.n, v.length, v.throughput, w_light);
}

// The camera side's part of weight_merge's denominator, which does not depend on the photon.
fn merge_camera_share(camera: SubpathMis, merge: MergeMis, camera_rev: f32) -> f32 {
    return camera.d_vcm * merge.vc + camera.d_vm * mis(camera_rev);
}

// The probability of running a camera vertex's merge query (VCM): the query adds at most
// max(beta rho) / (1 + the camera side's share) of the light arriving there; below tau it runs
// with probability bound / tau (subpath.rs: merge_survival).
fn merge_survival(camera: SubpathMis, merge: MergeMis, camera_rev: f32, throughput_albedo: f32, threshold: f32) -> f32 {
    let bound = throughput_albedo / (1.0 + merge_camera_share(camera, merge, camera_rev));
    if bound >= threshold || threshold <= 0.0 {
        return 1.0;
    }
    return bound / threshold;
}
