// The light pass of light tracing and BDPT: `src/cpu/light_path.rs` again, with the same names,
// steps and step comments. One light subpath per invocation, its non-specular vertices (the
// light point included) splatted into the pixels that see them (t = 1) and, for BDPT, stored in
// the pool for the camera pass.

// Whether a material scatters diffusely: diffuse surfaces, and emitters that also reflect.
fn is_diffuse(material: Material) -> bool {
    return material.kind == KIND_DIFFUSE || (material.kind == KIND_EMITTER && max_element(material.color) > 0.0);
}

// The longest full path (in edges) that the `max_bounces` fault lets through.
fn max_path_edges() -> u32 {
    return select(frame.max_bounces + 1u, frame.max_bounces, frame.max_bounces == 0xffffffffu);
}

// The camera's importance for a direction at cos theta to its axis (with the test-only fault
// that drops one cos theta).
fn splat_importance(cos_theta: f32, importance: f32) -> f32 {
    if frame.importance_missing_cos != 0u {
        return importance * cos_theta;
    }
    return importance;
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
    let bidirectional = frame.method == METHOD_BDPT;
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
    // importance and the geometry term toward the eye, against the camera subpath that
    // hits the emitter there (s = 0).
    let r = camera_raster(camera, light.p);
    if r.seen {
        let cos_l = -dot(light.n, r.dir);
        if cos_l > 0.0 && 1u <= max_path_edges() {
            let origin = offset_ray_origin(light.p, light.p_err, light.n, -r.dir);
            if !occluded(Ray(origin, camera.eye - origin), 1.0) {
                let importance = splat_importance(dot(r.dir, camera.forward), r.importance);
                let pdf_camera = importance * cos_l / r.dist2;
                var w = 1.0;
                if bidirectional {
                    w = weight_light_point_to_camera(pdf_camera, n_paths, light.pdf_area);
                }
                let value = light.le / light.pdf_area * (pdf_camera * w / n_paths);
                splat_add(splat_cell(r.y * camera.width + r.x), value);
            }
        }
    }

    var throughput = light.le * (emission.cos / (light.pdf_area * emission.pdf_dir));
    // The product of the BSDF weights alone, which Russian roulette looks at.
    var scattered = vec3<f32>(1.0);
    var m = mis_light(light.pdf_area, emission.pdf_dir, emission.cos);
    var ray = Ray(offset_ray_origin(light.p, light.p_err, light.n, emission.dir), emission.dir);
    var bounce = 0u;

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
        if diffuse {
            let n_facing = select(hit.n, -hit.n, cos_o < 0.0);

            // Step 4 - store the vertex for the camera subpaths (BDPT).
            if bidirectional && !full {
                let v = LightVertex(hit.p, max_element(hit.p_err), n_facing, hit.material, wo, length, throughput, NO_VERTEX, m.d_vcm, m.d_vc, m.d_vm, 0u);
                last = store_light_vertex(path, last, v);
                full = last == NO_VERTEX;
            }

            // Step 5 - connect to the camera (t = 1): splat alpha f W |cos| / dist^2 / N into
            // the pixel that sees the vertex, if nothing is in between.
            let rv = camera_raster(camera, hit.p);
            if rv.seen {
                let to_eye = -rv.dir;
                let bsdf = eval_diffuse(material.color, n_facing, wo, to_eye);
                if bsdf.pdf > 0.0 && length + 1u <= max_path_edges() {
                    let origin = offset_ray_origin(hit.p, hit.p_err, hit.n, to_eye);
                    if !occluded(Ray(origin, camera.eye - origin), 1.0) {
                        let importance = splat_importance(dot(rv.dir, camera.forward), rv.importance);
                        let pdf_camera = importance * bsdf.cos_i / rv.dist2;
                        var w = 1.0;
                        if bidirectional {
                            w = weight_to_camera(m, pdf_camera, n_paths, bsdf.pdf_rev);
                        }
                        let value = throughput * bsdf.f * (pdf_camera * w / n_paths);
                        splat_add(splat_cell(rv.y * camera.width + rv.x), value);
                    }
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
            m = mis_after_diffuse(m, cos_out, bs.pdf, abs(cos_o) * FRAC_1_PI);
        }
        if max_element(scattered) <= 0.0 {
            break;
        }
        ray = Ray(offset_ray_origin(hit.p, hit.p_err, hit.n, bs.wi), bs.wi);

        // Step 7 - Russian roulette, as on camera paths: from bounce RR_START_BOUNCE on,
        // continue with probability q = min(max(scattered), 0.95) and divide by q.
        if bounce >= RR_START_BOUNCE {
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
    trace_light_path(Sampler(frame.seed, path, frame.first_sample), path);
}
