// The path integrator: `src/cpu/path.rs` again, with the same names, the same steps in the same
// order and the same step comments. Unidirectional path tracing with next-event estimation and
// multiple importance sampling (power heuristic); Russian roulette, no maximum depth.
//
// A path is `start_path`, then `path_bounce` until it returns false, then `finish_path`: the
// CPU's `trace_path` for one sample. Here `render_pass` runs that sequence for all of a pass's
// samples of a pixel in one loop of bounces (path regeneration), in sample order. The CPU's
// renders split a bounce further (`shade_hit`, `add_next_event`, `end_bounce`) so that a round's
// shadow rays are traced together; step 4's light is added there before the next bounce's, and
// the grey-indirect snapshot of step 5 is taken in `end_bounce`, after it: the same sums.

const RR_START_BOUNCE: u32 = 3u;
const RR_MAX_SURVIVAL: f32 = 0.95;

// One camera sample's path between two bounces: the ray to trace next and what the path has
// gathered and carries so far.
struct PathState {
    ray: Ray,
    radiance: vec3<f32>,
    throughput: vec3<f32>,
    // Product of etap^2 over refractions; throughput x eta_scale is what roulette looks at, so
    // that radiance scaling at glass boundaries does not end paths inside glass.
    eta_scale: f32,
    // Solid-angle pdf of the BSDF sample that produced `ray`; 0 for the camera ray and after a
    // specular bounce (no light-sampling strategy competes there).
    bsdf_pdf: f32,
    bounce: u32,
    // `Faults::grey_indirect` only: the radiance gathered before the first diffuse bounce,
    // once `greying`.
    before_indirect: vec3<f32>,
    greying: bool,
}

// Step 1 - camera ray: a uniform point in the pixel (box filter) through the pinhole.
fn start_path(x: u32, y: u32, sampler: Sampler) -> PathState {
    let u_camera = draw4(sampler, DIM_CAMERA);
    let ray = camera_ray(frame.camera, x, y, u_camera.x, u_camera.y);
    return PathState(ray, vec3<f32>(0.0), vec3<f32>(1.0), 1.0, 0.0, 0u, vec3<f32>(0.0), false);
}

// Steps 2 to 6 of one bounce: traces `path.ray`, adds what it finds to `path.radiance` and
// prepares the next ray; false when the path has ended.
fn path_bounce(path: ptr<function, PathState>, sampler: Sampler) -> bool {
    // N light samples and one BSDF sample per vertex: Veach's multi-sample MIS weighs each
    // strategy by n_i · p_i (eq. 9.13), so N enters both weights and divides the NEE sum.
    let light_samples = max(frame.light_samples, 1u);
    let n_light = f32(light_samples);
    let bounce = (*path).bounce;

    // Step 2 - closest hit: the nearest surface along the ray over the BVH; nothing is
    // outside the scene, so a miss ends the path.
    let ray = (*path).ray;
    let candidate = traverse(ray, F32_MAX, false);
    if !candidate.found {
        return false;
    }
    let hit = surface_hit(ray, candidate);
    let material = materials[hit.material];
    let wo = -ray.d;
    let cos_o = dot(hit.n, wo);

    // Step 3 - emission: an emitter seen from its front. After the camera or a specular
    // bounce it is counted in full; after a diffuse bounce it is weighted by the power
    // heuristic against light sampling, whose pdf for this point is converted to solid
    // angle at the previous vertex (the ray's direction is unit, so hit.t is the distance).
    if material.kind == KIND_EMITTER && cos_o > 0.0 {
        let le = material.emission;
        if (*path).bsdf_pdf == 0.0 {
            (*path).radiance += (*path).throughput * le;
        } else {
            let light_pdf = area_to_solid_angle(emitter_pdf_area(hit.prim), hit.t * hit.t, cos_o);
            (*path).radiance += (*path).throughput * le * power_heuristic((*path).bsdf_pdf, n_light * light_pdf);
        }
    }

    // Step 4 - next-event estimation at diffuse surfaces: N times, choose an emitter
    // triangle by power and a uniform point on it, trace one shadow ray, and add
    // f · Le · cos θs / (N · p_ω(light)), with p_ω the area pdf converted to solid angle,
    // weighted by the power heuristic against BSDF sampling (p_ω(bsdf) = cos θs / pi).
    let u_light = draw4(sampler, dim_light(bounce));
    let albedo = material.color;
    let diffuse = material.kind == KIND_DIFFUSE || (material.kind == KIND_EMITTER && max_element(albedo) > 0.0);
    if material.kind == KIND_EMITTER && !diffuse {
        // A black emitter reflects nothing: the path ends here.
        return false;
    }
    if diffuse {
        let n_facing = select(hit.n, -hit.n, cos_o < 0.0);
        for (var j = 0u; j < light_samples; j++) {
            var u = u_light;
            if j > 0u {
                u = draw4(sampler, dim_light_extra(bounce, j));
            }
            let ls = sample_emitter(u.x, u.y, u.z);
            let link = link_to_emitter(hit.p, hit.p_err, hit.n, n_facing, ls);
            if link.found && !occluded(link.shadow, 1.0) {
                let f = albedo * FRAC_1_PI;
                let w = power_heuristic(n_light * link.light_pdf, link.cos_s * FRAC_1_PI);
                (*path).radiance += (*path).throughput * f * link.le * (link.cos_s * w / (n_light * link.light_pdf));
            }
        }
    }

    // Step 5 - scattering: sample the BSDF for the next direction; the throughput takes
    // the sample's weight f · |cos θi| / pdf.
    let u_bsdf = draw4(sampler, dim_bsdf(bounce));
    let bs = sample_bsdf(material, hit.n, wo, u_bsdf, TRANSPORT_RADIANCE);
    (*path).throughput *= bs.weight;
    if bs.pdf == 0.0 {
        (*path).throughput *= frame.specular_scale;
    }
    (*path).eta_scale *= bs.eta2;
    (*path).bsdf_pdf = bs.pdf;
    if frame.grey_indirect != 0u && bs.pdf > 0.0 && !(*path).greying {
        (*path).greying = true;
        (*path).before_indirect = (*path).radiance;
    }
    if max_element((*path).throughput) <= 0.0 {
        return false;
    }
    (*path).ray = Ray(offset_ray_origin(hit.p, hit.p_err, hit.n, bs.wi), bs.wi);

    // Step 6 - Russian roulette: from bounce RR_START_BOUNCE on, continue with probability
    // q = min(max(throughput) · eta_scale, 0.95) and divide by q, which keeps the estimator
    // unbiased (E[X / q · 1{u < q}] = E[X]) while ending low-throughput paths.
    if bounce >= RR_START_BOUNCE {
        let q = min(max_element((*path).throughput) * (*path).eta_scale, RR_MAX_SURVIVAL);
        if u_light.w >= q {
            return false;
        }
        (*path).throughput /= q;
    }
    (*path).bounce += 1u;
    return (*path).bounce < frame.max_bounces;
}

// The path's estimate; under `Faults::grey_indirect`, its indirect light replaced by its grey.
fn finish_path(path: PathState) -> vec3<f32> {
    if path.greying {
        let indirect = path.radiance - path.before_indirect;
        return path.before_indirect + vec3<f32>((indirect.x + indirect.y + indirect.z) / 3.0);
    }
    return path.radiance;
}

// One invocation per pixel of the dispatch's tile: the frame's samples of that pixel, added to
// the pass's sums. Under adaptive sampling (frame.run_count > 0), one invocation per pixel run
// instead, the tile a grid of them row by row: the run's samples of its pixel.
@compute @workgroup_size(8, 8, 1)
fn render_pass(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.tile_size.x || gid.y >= frame.tile_size.y || frame.sample_count == 0u {
        return;
    }
    var x = frame.tile_origin.x + gid.x;
    var y = frame.tile_origin.y + gid.y;
    var first = frame.first_sample;
    var end = first + frame.sample_count;
    if frame.run_count > 0u {
        let i = gid.y * frame.tile_size.x + gid.x;
        if i >= frame.run_count {
            return;
        }
        let run = pixel_runs[frame.run_offset + i];
        x = run.x % frame.camera.width;
        y = run.x / frame.camera.width;
        first = run.y;
        end = run.y + run.z;
    }
    let index = y * frame.camera.width + x;
    var sums = PixelSums();
    // Path regeneration (Novák et al., "GPU Computing: Interactive Path Tracing with Path
    // Regeneration", 2010): the lanes of a group run in lockstep, so a loop of samples around
    // a loop of bounces keeps every lane until the group's longest path of each sample ends.
    // One loop of bounces instead, where a lane whose path ended starts its pixel's next
    // sample at once: measured with `examples/lane_occupancy.rs`, 16 samples a lane keep 85 %
    // of 8 lanes busy bounce by bounce where one sample at a time keeps 56 %. Each sample is
    // the path a loop over samples would trace (its own streams), added in sample order.
    var s = first;
    var sampler = frame_sampler(index, s);
    var path = start_path(x, y, sampler);
    loop {
        if path_bounce(&path, sampler) {
            continue;
        }
        add_sample(&sums, s, finish_path(path));
        s += 1u;
        if s >= end {
            break;
        }
        sampler = frame_sampler(index, s);
        path = start_path(x, y, sampler);
    }
    add_to_pixel(x, y, sums);
}
