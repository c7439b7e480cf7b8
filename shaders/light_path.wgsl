// The light pass of light tracing, BDPT, SPPM and VCM: `src/cpu/light_path.rs` again, with the
// same names, steps and step comments. One light subpath per invocation, its non-specular
// vertices (the light point included) splatted into the pixels that see them (t = 1; not for
// SPPM) and, but for light tracing, stored in the pool for the camera pass; for BDPT, a
// subpath whose first hit is a planar mirror ends at the diffuse vertex after it (next-event
// estimation through the mirror takes those paths: planar_mirror.wgsl). Here each splat's
// visibility ray is traced where it is met; the CPU traces a chunk's splat rays together in SIMD
// packets (`PendingSplat`, `add_splats`), which splats the same values, and splat sums do not
// depend on their order.

// Whether a material scatters diffusely: diffuse surfaces, and emitters that also reflect.
fn is_diffuse(material: Material) -> bool {
    return material.kind == KIND_DIFFUSE || (material.kind == KIND_EMITTER && max_element(material.color) > 0.0);
}

// The longest full path (in edges) that the `max_bounces` fault lets through.
fn max_path_edges() -> u32 {
    return select(frame.max_bounces + 1u, frame.max_bounces, frame.max_bounces == 0xffffffffu);
}

// The camera's importance where it sees a point (with the test-only fault that drops one
// cos theta).
fn splat_importance(r: Raster) -> f32 {
    if frame.importance_missing_cos != 0u {
        return r.importance * dot(r.dir, frame.camera.forward);
    }
    return r.importance;
}

// n_c of pixel `index` (in the film band), kept in the fourth lane of its camera radiance.
fn camera_subpaths(index: u32) -> f32 {
    return camera_radiance[band_index(index)].w;
}

// Splats `value` into `pixel` if the surface point p sees the eye, tracing the visibility ray
// with probability shadow_survival of the value (drawing u) and dividing by it.
fn splat(pixel: u32, p: vec3<f32>, p_err: vec3<f32>, n: vec3<f32>, value: vec3<f32>, u: f32) {
    let q = shadow_survival(value, frame.shadow_threshold);
    if u >= q {
        return;
    }
    let eye = frame.camera.eye;
    let origin = offset_ray_origin(p, p_err, n, eye - p);
    if !occluded(Ray(origin, eye - origin), 1.0) {
        splat_add(splat_cell(band_index(pixel)), value / q);
    }
}

// Appends a vertex to light subpath `path`'s list in the pool, after `last` (NO_VERTEX for the
// first); returns the new last vertex, or NO_VERTEX when the pool is full (the vertex is still
// counted, so the camera pass sees the overflow and the host traces the iteration again in
// smaller waves).
fn store_light_vertex(path: u32, last: u32, v: LightVertex) -> u32 {
    let k = atomicAdd(&tallies[vertex_counter()], 1u);
    if k >= frame.vertex_capacity {
        return NO_VERTEX;
    }
    light_vertices[k] = v;
    if last == NO_VERTEX {
        atomicStore(&tallies[path_head(path)], k);
    } else {
        light_vertices[last].next = k;
    }
    return k;
}

// Traces light subpath `path` of `sampler`: splats its connections to the camera and, for BDPT,
// stores its diffuse vertices.
fn trace_light_path(sampler: Sampler, path: u32) {
    let n_paths = f32(frame.n_light_paths);
    // MIS-weighted splats (not light tracing's weight 1), stored vertices (not light tracing),
    // splats at all (not SPPM or photon-map).
    let bidirectional = frame.method != METHOD_LIGHT;
    let stores = frame.method != METHOD_LIGHT;
    let splats_to_camera = frame.method != METHOD_SPPM && frame.method != METHOD_PHOTON_MAP;
    // The light's first hits are direct light, which photon-map takes by next-event estimation
    // alone.
    let stores_first_hits = frame.method != METHOD_PHOTON_MAP;
    // Where roulette starts: earlier where camera vertices connect to this subpath's.
    let rr_start = select(
        RR_START_BOUNCE,
        LIGHT_SUBPATH_RR_START_BOUNCE,
        frame.method == METHOD_BDPT || frame.method == METHOD_VCM || frame.method == METHOD_VCM_FULL,
    );
    let camera = frame.camera;
    atomicStore(&tallies[path_head(path)], NO_VERTEX);
    // The last vertex stored, and whether the pool ran out (then nothing more is stored).
    var last = NO_VERTEX;
    var full = false;

    // Step 1 - emission: an emitter point chosen by power, uniformly on its area, and a
    // cosine-distributed direction from its front.
    let emission = sample_emission(draw4(sampler, DIM_EMISSION), draw4(sampler, DIM_EMISSION_DIR));
    let light = emission.point;

    // Step 2 - the light point seen by the camera (s = 1, t = 1): Le / p_A times the
    // importance and the geometry term toward the eye, against the camera subpaths that
    // hit the emitter there (s = 0).
    let r = camera_raster(camera, light.p);
    if r.seen && splats_to_camera && in_film_band(r.y) {
        let cos_l = -dot(light.n, r.dir);
        if cos_l > 0.0 && 1u <= max_path_edges() {
            let pixel = r.y * camera.width + r.x;
            // The measurement W |cos| / dist^2, which times n_c is also the camera's density of
            // the point.
            let g_camera = splat_importance(r) * cos_l / r.dist2;
            var w = 1.0;
            if bidirectional {
                w = weight_light_point_to_camera(g_camera * camera_subpaths(pixel), n_paths, light.pdf_area);
            }
            let value = light.le / light.pdf_area * (g_camera * w / n_paths);
            splat(pixel, light.p, light.p_err, light.n, value, draw4(sampler, DIM_EMISSION).w);
        }
    }

    var throughput = light.le * (emission.cos / (light.pdf_area * emission.pdf_dir));
    // The product of the BSDF weights alone, which Russian roulette looks at.
    var scattered = vec3<f32>(1.0);
    var m = mis_light(light.pdf_area, emission.pdf_dir, emission.cos, iteration_merge());
    var ray = Ray(offset_ray_origin(light.p, light.p_err, light.n, emission.dir), emission.dir);
    var bounce = 0u;
    // Next-event estimation through planar mirrors takes the paths whose light end is the light
    // point, a planar mirror and a diffuse vertex (BDPT; planar_mirror.wgsl): the primitive of
    // this subpath's first hit tells.
    let through_mirrors = takes_mirror_light(frame.method == METHOD_BDPT || frame.method == METHOD_VCM || frame.method == METHOD_VCM_FULL);
    var first_prim = PRIM_PADDING;

    loop {
        // Step 3 - closest hit; the quantities turn the direction's density into an area
        // density at the hit.
        let candidate = traverse(ray, F32_MAX, false);
        if !candidate.found {
            break;
        }
        let hit = surface_hit(ray, candidate);
        let material = materials[hit.material];
        let wo = -ray.d;
        let cos_o = dot(hit.n, wo);
        if density_vanishes(cos_o) && frame.continue_at_vanishing_density == 0u {
            // A grazing hit that no f32 density can describe ends the subpath.
            break;
        }
        m = mis_at_hit(m, hit.t * hit.t, abs(cos_o));
        let length = bounce + 1u;
        if length >= max_path_edges() {
            break;
        }

        let diffuse = is_diffuse(material);
        if material.kind == KIND_EMITTER && !diffuse {
            // A black emitter absorbs.
            break;
        }
        if length == 1u {
            first_prim = hit.prim;
        } else if length == 2u && through_mirrors && starts_by_a_mirror(first_prim, diffuse) {
            // The light came to this diffuse vertex from a planar mirror: every path through it
            // is next-event estimation's through the mirror (weight 1), so the subpath stores
            // and splats nothing more.
            break;
        }
        if diffuse {
            let n_facing = select(hit.n, -hit.n, cos_o < 0.0);

            // Step 4 - store the vertex for the camera subpaths to connect to and merge with
            // (BDPT, VCM, SPPM, photon-map but for first hits).
            if stores && !full && (length > 1u || stores_first_hits) {
                let v = LightVertex(hit.p, max_element(hit.p_err), n_facing, hit.material, wo, length, throughput, NO_VERTEX, m.d_vcm, m.d_vc, m.d_vm, path);
                last = store_light_vertex(path, last, v);
                full = last == NO_VERTEX;
            }

            // Step 5 - connect to the camera (t = 1): splat alpha f W |cos| / dist^2 / N into
            // the pixel that sees the vertex.
            let rv = camera_raster(camera, hit.p);
            if rv.seen && splats_to_camera && in_film_band(rv.y) {
                let bsdf = eval_diffuse(material.color, n_facing, wo, -rv.dir);
                if bsdf.pdf > 0.0 && length < max_path_edges() {
                    let pixel = rv.y * camera.width + rv.x;
                    let g_camera = splat_importance(rv) * bsdf.cos_i / rv.dist2;
                    var w = 1.0;
                    if bidirectional {
                        // A camera subpath's merge here would use this vertex's radius, by its
                        // distance from the eye (vcm: within its clearance).
                        let share = merge_share(hit.p, hit.prim, footprint_share(sqrt(rv.dist2)));
                        let merge = merge_within(iteration_merge(), share);
                        w = weight_to_camera(m, merge, g_camera * camera_subpaths(pixel), n_paths, bsdf.pdf_rev);
                    }
                    let value = throughput * bsdf.f * (g_camera * w / n_paths);
                    splat(pixel, hit.p, hit.p_err, hit.n, value, draw4(sampler, dim_splat(bounce)).x);
                }
            }
        }

        // Step 6 - scattering: sample the adjoint BSDF; the quantities take the new
        // direction's densities (a specular bounce leaves only its cosine).
        let u = draw4(sampler, dim_light_bounce(bounce));
        let bs = sample_bsdf(material, hit.n, wo, u, TRANSPORT_IMPORTANCE);
        let cos_out = abs(dot(hit.n, bs.wi));
        if bs.pdf == 0.0 {
            scattered *= bs.weight * frame.specular_scale;
            throughput *= bs.weight * frame.specular_scale;
            m = mis_after_specular(m, cos_out);
        } else {
            scattered *= bs.weight;
            throughput *= bs.weight;
            m = mis_after_diffuse(m, cos_out, bs.pdf, abs(cos_o) * FRAC_1_PI, iteration_merge());
        }
        if max_element(scattered) <= 0.0 {
            break;
        }
        ray = Ray(offset_ray_origin(hit.p, hit.p_err, hit.n, bs.wi), bs.wi);

        // Step 7 - Russian roulette, as on camera paths but from bounce rr_start on
        // (LIGHT_SUBPATH_RR_START_BOUNCE for BDPT and VCM, RR_START_BOUNCE otherwise): continue
        // with probability q = min(max(scattered), 0.95) and divide by q.
        if bounce >= rr_start {
            let q = min(max_element(scattered), RR_MAX_SURVIVAL);
            if u.w >= q {
                break;
            }
            scattered /= q;
            throughput /= q;
        }
        bounce += 1u;
    }
}

// One invocation per light subpath of the dispatch's range.
@compute @workgroup_size(64, 1, 1)
fn light_pass(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.path_count {
        return;
    }
    let path = frame.path_origin + gid.x;
    trace_light_path(frame_sampler(path, frame.first_sample), path);
}
