// The camera pass of bidirectional path tracing: `src/cpu/bdpt.rs` again, with the same names,
// steps and step comments. One camera subpath per pixel (n_c where the pixel sees a mirror or
// glass), and at each of its vertices every strategy that ends there: the emitter it hits (s = 0),
// next-event estimation (s = 1) and a connection to each stored vertex of the pixel's light subpath
// (s >= 2), each with its MIS weight (subpath.wgsl) and its visibility ray rouletted by its
// contribution; BDPT's next-event estimation also aims at the light's image in each planar mirror,
// and takes the paths it makes alone (step 4b, planar_mirror.wgsl). With photons, the camera pass
// of the merging methods: vcm-full adds the merges at every diffuse vertex (hash_grid.wgsl); vcm
// ends the camera subpath at its first diffuse vertex, after its connections and merge there; SPPM
// merges at the first diffuse vertex alone. Here each visibility ray is traced where it is met; the
// CPU keeps a tile's visibility rays and the terms they multiply (`CameraTerms`), traces the rays
// together in SIMD packets and then sums each subpath's terms in the order met, which gives the
// same sums.

// Whether surface points a and b (points, error bounds, unit normals) see each other, after
// Russian roulette on the ray by `value`, the contribution it would bring (drawing u): the factor
// to multiply the contribution by, 1 / q where the ray was traced and found clear, else 0
// (`CameraPass::visibility`, which leaves the ray to be traced with the tile's).
fn visibility(a_p: vec3<f32>, a_err: vec3<f32>, a_n: vec3<f32>, b_p: vec3<f32>, b_err: vec3<f32>, b_n: vec3<f32>, value: vec3<f32>, u: f32) -> f32 {
    let q = shadow_survival(value, frame.shadow_threshold);
    if u >= q {
        return 0.0;
    }
    return visibility_after_roulette(a_p, a_err, a_n, b_p, b_err, b_n, 1.0 / q);
}

// `factor` (1 / q of a roulette already passed) where surface points a and b see each other,
// else 0 (`CameraPass::visibility_after_roulette`, which leaves the ray to be traced with the
// tile's).
fn visibility_after_roulette(a_p: vec3<f32>, a_err: vec3<f32>, a_n: vec3<f32>, b_p: vec3<f32>, b_err: vec3<f32>, b_n: vec3<f32>, factor: f32) -> f32 {
    let to_b = b_p - a_p;
    let origin = offset_ray_origin(a_p, a_err, a_n, to_b);
    let end = offset_ray_origin(b_p, b_err, b_n, -to_b);
    if occluded(Ray(origin, end - origin), 1.0) {
        return 0.0;
    }
    return factor;
}

// The radiance that one camera subpath of pixel (x, y) gathers by the strategies with t >= 2,
// connecting to light subpath `path` of the pool; the pixel traces n_c of them. `own`: the pool
// holds this pixel's light subpath (this wave traced it). A merging iteration too large for one
// pool runs in waves, each followed by a camera pass over every pixel: a pixel takes emission,
// next-event estimation and its connections in its own wave, and merges with each wave's
// photons, so that over the waves it takes every strategy once, as in one wave.
fn trace_camera_path(x: u32, y: u32, n_c: f32, sampler: Sampler, path: u32, own: bool) -> vec3<f32> {
    let n_paths = f32(frame.n_light_paths);
    let max_edges = max_path_edges();
    // Step 1 - camera ray: a uniform point in the pixel (box filter) through the pinhole; its
    // direction's density is the importance W, n_c times over.
    let u_camera = draw4(sampler, DIM_CAMERA);
    var ray = camera_ray(frame.camera, x, y, u_camera.x, u_camera.y);
    let cos_camera = dot(ray.d, frame.camera.forward);
    var m = mis_camera(n_paths, n_c * camera_importance(frame.camera, cos_camera));

    var radiance = vec3<f32>(0.0);
    var throughput = vec3<f32>(1.0);
    // Product of etap^2 over refractions, for Russian roulette (as in path.wgsl).
    var eta_scale = 1.0;
    var bounce = 0u;
    // Next-event estimation through planar mirrors (BDPT): whether the vertex before this
    // one was diffuse, and whether this one was reached from a diffuse vertex by way of a planar
    // mirror (planar_mirror.wgsl: such emission is that strategy's alone).
    let through_mirrors = takes_mirror_light(connects());
    var previous_diffuse = false;
    var by_a_mirror = false;
    // The distance from the eye along the subpath, which sets a vertex's merge radius
    // (footprint_share).
    var travelled = 0.0;

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
        travelled += hit.t;
        let cos_o = dot(hit.n, wo);
        if density_vanishes(cos_o) && frame.continue_at_vanishing_density == 0u {
            // A grazing hit that no f32 density can describe ends the subpath.
            break;
        }
        m = mis_at_hit(m, hit.t * hit.t, abs(cos_o));
        // Edges of the camera subpath up to this vertex.
        let depth = bounce + 1u;

        // Step 3 - emission (s = 0): an emitter seen from its front, weighted against the
        // light point taken by next-event estimation or by a light subpath (SPPM meets it
        // only through mirrors and glass, where nothing else can: weight 1). Seen from a
        // diffuse vertex in a planar mirror, it is next-event estimation's (step 4b).
        if own && material.kind == KIND_EMITTER && cos_o > 0.0 && depth <= max_edges && !by_a_mirror {
            let pdf_area = emitter_pdf_area(hit.prim);
            var w = 1.0;
            if connects() {
                w = weight_emission(m, pdf_area, cos_o * FRAC_1_PI);
            }
            radiance += throughput * material.emission * w;
        }

        let u_light = draw4(sampler, dim_light(bounce));
        let u_bsdf = draw4(sampler, dim_bsdf(bounce));
        let diffuse = is_diffuse(material);
        if material.kind == KIND_EMITTER && !diffuse {
            // A black emitter reflects nothing: the path ends here.
            break;
        }
        if diffuse {
            let n_facing = select(hit.n, -hit.n, cos_o < 0.0);
            let albedo = material.color;
            let pdf_rev = abs(cos_o) * FRAC_1_PI;
            // The merge radius here as a share of the iteration's largest (`merge_share`: by the
            // distance from the eye, and in vcm within the vertex's clearance), and merging's
            // MIS constants for it.
            let share = merge_share(hit.p, hit.prim, footprint_share(travelled));
            let merge = merge_within(iteration_merge(), share);

            // Step 4 - next-event estimation (s = 1): an emitter point chosen by power,
            // uniformly on its area, one shadow ray; weighted against BSDF sampling (s = 0)
            // and against the light subpath that would start there (s = 2).
            let ls = sample_emitter(u_light.x, u_light.y, u_light.z);
            let to_light = ls.p - hit.p;
            let dist2 = dot(to_light, to_light);
            let wi = to_light / sqrt(dist2);
            let cos_l = -dot(ls.n, wi);
            let bsdf = eval_diffuse(albedo, n_facing, wo, wi);
            if own && connects() && depth < max_edges && bsdf.pdf > 0.0 && cos_l > 0.0 && dist2 > 0.0 {
                let pdf_light = area_to_solid_angle(ls.pdf_area, dist2, cos_l);
                let pdf_emit = cos_l * FRAC_1_PI * bsdf.cos_i / dist2;
                let w = weight_next_event(m, merge, bsdf.pdf, pdf_light, pdf_emit, pdf_rev);
                let value = throughput * bsdf.f * ls.le * (bsdf.cos_i * w / pdf_light);
                radiance += value * visibility(hit.p, hit.p_err, hit.n, ls.p, ls.p_err, ls.n, value, u_bsdf.w);
            }

            // Step 4b - next-event estimation through each planar mirror: the same emitter
            // point, reflected in the mirror's plane, is a light of the same area density; the
            // path x -> m -> y has the image's geometry term and the mirror's reflectance, and
            // weight 1 (planar_mirror.wgsl). A closest-hit ray finds m on the mirror with x m
            // clear, a shadow ray m y.
            if own && through_mirrors && depth + 1u < max_edges {
                let u_mirror = draw4(sampler, dim_mirror(bounce));
                for (var i = 0u; i < frame.planar_mirror_count; i++) {
                    let mirror = frame.planar_mirrors[i];
                    let im = image(mirror, hit.p, ls.p, ls.n);
                    if !im.found {
                        continue;
                    }
                    let to_image = im.y_image - hit.p;
                    let dist2 = dot(to_image, to_image);
                    let wi = to_image / sqrt(dist2);
                    let cos_l = -dot(im.n_image, wi);
                    let bsdf = eval_diffuse(albedo, n_facing, wo, wi);
                    if bsdf.pdf <= 0.0 || cos_l <= 0.0 || dist2 <= 0.0 {
                        continue;
                    }
                    // The mirror's reflectance (a specular bounce: the test-only specular_scale
                    // too).
                    let reflectance = materials[mirror.material].color * frame.specular_scale;
                    let value = throughput * bsdf.f * reflectance * ls.le * (bsdf.cos_i * cos_l / (dist2 * ls.pdf_area));
                    let q = shadow_survival(value, frame.shadow_threshold);
                    if u_mirror[i] >= q {
                        continue;
                    }
                    let to_mirror = Ray(offset_ray_origin(hit.p, hit.p_err, hit.n, wi), wi);
                    let candidate = traverse(to_mirror, F32_MAX, false);
                    if !candidate.found {
                        continue;
                    }
                    let mirror_hit = surface_hit(to_mirror, candidate);
                    if planar_mirror_of(mirror_hit.prim) != i {
                        continue;
                    }
                    radiance += value * visibility_after_roulette(mirror_hit.p, mirror_hit.p_err, mirror_hit.n, ls.p, ls.p_err, ls.n, 1.0 / q);
                }
            }

            // Step 5 - connections (s >= 2): to each vertex of this pixel's light subpath, one
            // shadow ray each; the contribution is beta f_c G f_l alpha, weighted against every
            // other strategy on both sides.
            var k = select(NO_VERTEX, atomicLoad(&tallies[path_head(path)]), own && connects());
            var i = 0u;
            while k != NO_VERTEX {
                let v = light_vertices[k];
                k = v.next;
                i += 1u;
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
                let g = camera_bsdf.cos_i * light_bsdf.cos_i / dist2;
                let light_mis = SubpathMis(v.d_vcm, v.d_vc, v.d_vm);
                let w = weight_connection(
                    m,
                    light_mis,
                    merge,
                    camera_bsdf.pdf * light_bsdf.cos_i / dist2,
                    camera_bsdf.pdf_rev,
                    light_bsdf.pdf * camera_bsdf.cos_i / dist2,
                    light_bsdf.pdf_rev,
                );
                let value = throughput * camera_bsdf.f * light_bsdf.f * v.throughput * (g * w);
                let u = draw4(sampler, dim_connection(bounce, i - 1u))[(i - 1u) % 4u];
                radiance += value * visibility(hit.p, hit.p_err, hit.n, v.p, vec3<f32>(v.p_err), v.n, value, u);
            }

            // Step 6 - merging (VCM, SPPM): every photon of the iteration within r on the same
            // side of the surface, counted with the disk kernel 1 / (pi r^2 N) times f alpha,
            // weighted against every other strategy (SPPM: 1). The photon is taken as arrived
            // here: Lambert's f = rho / pi, and the densities of its direction use its own
            // normal's cosine, which stays positive across the disk. (The CPU begins this
            // query at the hit and prefetches it during steps 4 and 5; here other invocations
            // hide its memory latency, and the query is the same.) VCM's query is rouletted by
            // the bound on what it can add: run with probability q, divided by q. Every wave of
            // merging draws the same number, so a vertex merges with all waves or none. Within
            // this vertex's radius share * r: the kernel's 1 / (pi r^2 N) and the light side's
            // term (vc) scale with it.
            var q_merge = 1.0;
            if merges() && connects() {
                q_merge = merge_survival(m, merge, pdf_rev, max_element(throughput * albedo), frame.merge_rr_threshold);
            }
            if merges() && (q_merge >= 1.0 || draw4(sampler, dim_merge(bounce)).x < q_merge) {
                var gathered = vec3<f32>(0.0);
                let camera_share = merge_camera_share(m, merge, pdf_rev);
                // The photon's record holds its light side's share at the iteration's radius
                // (PhotonRecord); within share * r it scales as vc, by 1 / mis(share^2).
                let vc_share = mis(share * share);
                // As on the CPU: at share 1, (1 * r_i)^2 is the grid's own r_i^2 to the bit.
                let radius = share * frame.merge_radius;
                let radius2 = radius * radius;
                let q = query_buckets(hit.p, share);
                for (var j = 0u; j < q.n; j++) {
                    let b = q.b[j];
                    let end = atomicLoad(&grid_starts[b + 1u]);
                    for (var e = atomicLoad(&grid_starts[b]); e < end; e++) {
                        let d = grid_entries[e].xyz - hit.p;
                        if dot(d, d) >= radius2 {
                            continue;
                        }
                        let photon = photon_records[e];
                        if depth + photon.length > max_edges || dot(photon.n, n_facing) <= 0.0 {
                            continue;
                        }
                        // subpath.rs: weight_merge, its two sides added as the CPU adds them.
                        var w = 1.0;
                        if connects() {
                            w = 1.0 / (photon.w_light / vc_share + 1.0 + camera_share);
                        }
                        gathered += photon.throughput * w;
                    }
                }
                if frame.merge_rr_undivided != 0u {
                    q_merge = 1.0;
                }
                radiance += throughput * albedo * gathered * (FRAC_1_PI * frame.merge_normalization / (share * share) / q_merge);
            }
            if !iteration_merge().camera_goes_on {
                // SPPM and VCM end the camera subpath at its first diffuse vertex
                // (subpath.rs, "VCM at the first diffuse vertex").
                break;
            }
        }

        // Step 7 - scattering: sample the BSDF for the next direction; the throughput takes
        // the sample's weight and the quantities its densities.
        let bs = sample_bsdf(material, hit.n, wo, u_bsdf, TRANSPORT_RADIANCE);
        let cos_out = abs(dot(hit.n, bs.wi));
        throughput *= bs.weight;
        if bs.pdf == 0.0 {
            throughput *= frame.specular_scale;
            m = mis_after_specular(m, cos_out);
        } else {
            m = mis_after_diffuse(m, cos_out, bs.pdf, abs(cos_o) * FRAC_1_PI, iteration_merge());
        }
        eta_scale *= bs.eta2;
        if max_element(throughput) <= 0.0 || depth >= max_edges {
            break;
        }
        // The light end (emitter, this vertex, the one before) that the partition gives to step
        // 4b: the predicate the light pass applies to its first two hits.
        by_a_mirror = through_mirrors && starts_by_a_mirror(hit.prim, previous_diffuse);
        previous_diffuse = diffuse;
        ray = Ray(offset_ray_origin(hit.p, hit.p_err, hit.n, bs.wi), bs.wi);

        // Step 8 - Russian roulette, as in path.wgsl: from bounce RR_START_BOUNCE on, continue
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

// One invocation per pixel of the dispatch's tile, for one iteration: the pixel's camera subpath,
// connected to light subpath (pixel index mod N), where the light pass of this wave has just
// traced it (light subpaths frame.path_origin .. + frame.path_count). Its radiance waits in
// `camera_radiance` for the resolve pass, which adds the splats: stored by the pixel's first camera
// pass of the iteration, added to by the later waves of a merging iteration. The light vertices the
// wave asked for are recorded in the iteration's image cell: if they overflowed the pool, the
// resolve pass drops the iteration and the host traces it again.
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
    // The pixel's n_c camera subpaths, averaged, each connecting to light subpath index mod N;
    // the k-th draws the streams of pixel index + k w h (a camera subpath's own blocks there:
    // light subpaths stop at N <= w h).
    let n_c = camera_radiance[band_index(index)].w;
    let path = index % frame.n_light_paths;
    let own = path >= frame.path_origin && path - frame.path_origin < frame.path_count;
    // Without merging, a pixel has nothing to do in the waves of other light subpaths; its own
    // wave stores its radiance.
    if !own && !merges() {
        return;
    }
    let pixels = frame.camera.width * frame.camera.height;
    var radiance = vec3<f32>(0.0);
    for (var k = 0u; k < u32(n_c); k++) {
        let sampler = frame_sampler(index + k * pixels, frame.first_sample);
        radiance += trace_camera_path(x, y, n_c, sampler, path, own);
    }
    // BDPT's pixels are each in one wave; a merging iteration's first wave covers all.
    var before = vec3<f32>(0.0);
    if merges() && frame.path_origin > 0u {
        before = camera_radiance[band_index(index)].xyz;
    }
    camera_radiance[band_index(index)] = vec4<f32>(before + radiance / n_c, n_c);
}
