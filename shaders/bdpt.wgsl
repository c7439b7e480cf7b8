// The camera pass of bidirectional path tracing: `src/cpu/bdpt.rs` again, with the same names,
// steps and step comments. One camera subpath per pixel, and at each of its vertices every
// strategy that ends there: the emitter it hits (s = 0), next-event estimation (s = 1) and a
// connection to each stored vertex of the pixel's light subpath (s >= 2), each with its MIS
// weight (subpath.wgsl).

// The radiance that the camera subpath of pixel (x, y) gathers by the strategies with t >= 2,
// connecting to light subpath `path` of the pool.
fn trace_camera_path(x: u32, y: u32, sampler: Sampler, path: u32) -> vec3<f32> {
    let n_paths = f32(frame.n_light_paths);
    let max_edges = max_path_edges();
    // Step 1 - camera ray: a uniform point in the pixel (box filter) through the pinhole; its
    // direction's density is the importance W.
    let u_camera = draw4(sampler, DIM_CAMERA);
    var ray = camera_ray(frame.camera, x, y, u_camera.x, u_camera.y);
    let cos_camera = dot(ray.d, frame.camera.forward);
    var m = mis_camera(n_paths, camera_importance(frame.camera, cos_camera));

    var radiance = vec3<f32>(0.0);
    var throughput = vec3<f32>(1.0);
    // Product of etap^2 over refractions, for Russian roulette (as in path.wgsl).
    var eta_scale = 1.0;
    var bounce = 0u;

    loop {
        // Step 2 - closest hit; the quantities turn the direction's density into an area
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
        // Edges of the camera subpath up to this vertex.
        let depth = bounce + 1u;

        // Step 3 - emission (s = 0): an emitter seen from its front, weighted against the
        // light point taken by next-event estimation or by a light subpath.
        if material.kind == KIND_EMITTER && cos_o > 0.0 && depth <= max_edges {
            let pdf_area = emitter_pdf_area(hit.prim);
            let w = weight_emission(m, pdf_area, cos_o * FRAC_1_PI);
            radiance += throughput * material.emission * w;
        }

        let u_light = draw4(sampler, dim_light(bounce));
        let diffuse = is_diffuse(material);
        if material.kind == KIND_EMITTER && !diffuse {
            // A black emitter reflects nothing: the path ends here.
            break;
        }
        if diffuse {
            let n_facing = select(hit.n, -hit.n, cos_o < 0.0);
            let albedo = material.color;
            let pdf_rev = abs(cos_o) * FRAC_1_PI;

            // Step 4 - next-event estimation (s = 1): an emitter point chosen by power,
            // uniformly on its area, one shadow ray; weighted against BSDF sampling (s = 0)
            // and against the light subpath that would start there (s = 2).
            let ls = sample_emitter(u_light.x, u_light.y, u_light.z);
            let to_light = ls.p - hit.p;
            let dist2 = dot(to_light, to_light);
            let wi = to_light / sqrt(dist2);
            let cos_l = -dot(ls.n, wi);
            let bsdf = eval_diffuse(albedo, n_facing, wo, wi);
            if bsdf.pdf > 0.0 && cos_l > 0.0 && dist2 > 0.0 && depth + 1u <= max_edges {
                let origin = offset_ray_origin(hit.p, hit.p_err, hit.n, wi);
                let light_point = offset_ray_origin(ls.p, ls.p_err, ls.n, -wi);
                if !occluded(Ray(origin, light_point - origin), 1.0) {
                    let pdf_light = area_to_solid_angle(ls.pdf_area, dist2, cos_l);
                    let pdf_emit = cos_l * FRAC_1_PI * bsdf.cos_i / dist2;
                    let w = weight_next_event(m, bsdf.pdf, pdf_light, pdf_emit, pdf_rev);
                    radiance += throughput * bsdf.f * ls.le * (bsdf.cos_i * w / pdf_light);
                }
            }

            // Step 5 - connections (s >= 2): to each vertex of this pixel's light subpath, one
            // shadow ray each; the contribution is beta f_c G f_l alpha, weighted against every
            // other strategy on both sides.
            var k = atomicLoad(&tallies[path_head(path)]);
            while k != NO_VERTEX {
                let v = light_vertices[k];
                k = v.next;
                if depth + 1u + v.length > max_edges {
                    continue;
                }
                let to_light = v.p - hit.p;
                let dist2 = dot(to_light, to_light);
                let dir = to_light / sqrt(dist2);
                let camera_bsdf = eval_diffuse(albedo, n_facing, wo, dir);
                let light_bsdf = eval_diffuse(materials[v.material].color, v.n, v.wo, -dir);
                if camera_bsdf.pdf <= 0.0 || light_bsdf.pdf <= 0.0 || dist2 <= 0.0 {
                    continue;
                }
                let origin = offset_ray_origin(hit.p, hit.p_err, hit.n, dir);
                let light_point = offset_ray_origin(v.p, vec3<f32>(v.p_err), v.n, -dir);
                if occluded(Ray(origin, light_point - origin), 1.0) {
                    continue;
                }
                let g = camera_bsdf.cos_i * light_bsdf.cos_i / dist2;
                let light_mis = SubpathMis(v.d_vcm, v.d_vc, v.d_vm);
                let w = weight_connection(
                    m,
                    light_mis,
                    camera_bsdf.pdf * light_bsdf.cos_i / dist2,
                    camera_bsdf.pdf_rev,
                    light_bsdf.pdf * camera_bsdf.cos_i / dist2,
                    light_bsdf.pdf_rev,
                );
                radiance += throughput * camera_bsdf.f * light_bsdf.f * v.throughput * (g * w);
            }
        }

        // Step 6 - scattering: sample the BSDF for the next direction; the throughput takes
        // the sample's weight and the quantities its densities.
        let u_bsdf = draw4(sampler, dim_bsdf(bounce));
        let bs = sample_bsdf(material, hit.n, wo, u_bsdf, TRANSPORT_RADIANCE);
        let cos_out = abs(dot(hit.n, bs.wi));
        throughput *= bs.weight;
        if bs.pdf == 0.0 {
            throughput *= frame.specular_scale;
            m = mis_after_specular(m, cos_out);
        } else {
            m = mis_after_diffuse(m, cos_out, bs.pdf, abs(cos_o) * FRAC_1_PI);
        }
        eta_scale *= bs.eta2;
        if max_element(throughput) <= 0.0 || depth >= max_edges {
            break;
        }
        ray = Ray(offset_ray_origin(hit.p, hit.p_err, hit.n, bs.wi), bs.wi);

        // Step 7 - Russian roulette, as in path.wgsl: from bounce RR_START_BOUNCE on, continue
        // with probability q = min(max(throughput) · eta_scale, 0.95) and divide by q.
        if bounce >= RR_START_BOUNCE {
            let q = min(max_element(throughput) * eta_scale, RR_MAX_SURVIVAL);
            if u_light.w >= q {
                break;
            }
            throughput /= q;
        }
        bounce += 1u;
    }
    return radiance;
}

// One invocation per pixel of the dispatch's tile, for one iteration: the pixel's camera
// subpath, connected to the light subpath of the same index, which the light pass of this wave
// has just traced. Its radiance waits in `camera_radiance` for the resolve pass, which adds the
// splats. The light vertices the wave asked for are recorded in the iteration's image cell: if
// they overflowed the pool, the resolve pass drops the iteration and the host traces it again.
@compute @workgroup_size(8, 8, 1)
fn camera_pass(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let asked = atomicLoad(&tallies[vertex_counter()]);
    if lid == 0u {
        atomicMax(&tallies[image_cell(frame.slot) + CELL_VERTICES], asked);
    }
    if gid.x >= frame.tile_size.x || gid.y >= frame.tile_size.y || asked > frame.vertex_capacity {
        return;
    }
    let x = frame.tile_origin.x + gid.x;
    let y = frame.tile_origin.y + gid.y;
    let index = y * frame.camera.width + x;
    let radiance = trace_camera_path(x, y, Sampler(frame.seed, index, frame.first_sample), index);
    camera_radiance[index] = vec4<f32>(radiance, 0.0);
}
