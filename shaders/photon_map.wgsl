// Photon mapping in Jensen's two-pass form, the camera pass of `--method photon-map`:
// `src/cpu/photon_map.rs` again, with the same names, steps and step comments. The light pass
// (light_path.wgsl) has stored the iteration's photons but for the light's first hits; a photon
// whose d_vm is 0 came from the light by mirrors and glass alone (the caustic map), one whose d_vm
// is above 0 scattered diffusely before (the global map). At the first diffuse point x the camera
// sees: next-event estimation, the caustic map, and final gathering, one cosine-sampled ray
// through mirrors and glass to the first diffuse point y, which adds y's direct light and both
// maps. Each density estimate counts the photons within the fixed radius r (the hash grid of
// hash_grid.wgsl). A merging iteration too large for one pool runs in waves, each followed by a
// camera pass over every pixel: a pixel takes emission and next-event estimation in its own wave
// and the density estimates of each wave's photons, so that over the waves it takes each term
// once, as in one wave.

// Which photons a density estimate counts (`PhotonMap`).
const PHOTON_MAP_CAUSTIC: u32 = 0u;
const PHOTON_MAP_CAUSTIC_AND_GLOBAL: u32 = 1u;

// The density estimate of `map` at diffuse point p, seen from the side of n_facing, reached by a
// camera subpath of `depth` edges: the sum of alpha / (pi r^2 N) over the photons within r on that
// side whose paths, joined to the camera subpath's, stay within the edges the max_bounces fault
// allows; times rho / pi it is the reflected radiance.
fn density(p: vec3<f32>, n_facing: vec3<f32>, depth: u32, map: u32) -> vec3<f32> {
    let max_edges = max_path_edges();
    let radius2 = frame.merge_radius * frame.merge_radius;
    var gathered = vec3<f32>(0.0);
    let q = query_buckets(p, 1.0);
    for (var j = 0u; j < q.n; j++) {
        let b = q.b[j];
        let end = atomicLoad(&grid_starts[b + 1u]);
        for (var e = atomicLoad(&grid_starts[b]); e < end; e++) {
            let d = grid_entries[e].xyz - p;
            if dot(d, d) >= radius2 {
                continue;
            }
            let photon = photon_records[e];
            // d_vm > 0 (the record's w_light without connections): the photon scattered
            // diffusely before (the global map).
            let caustic = photon.w_light <= 0.0;
            if (map == PHOTON_MAP_CAUSTIC && !caustic) || depth + photon.length > max_edges || dot(photon.n, n_facing) <= 0.0 {
                continue;
            }
            gathered += photon.throughput;
        }
    }
    return gathered * frame.merge_normalization;
}

// The radiance that one camera sample of pixel (x, y) gathers. `own`: this wave is the pixel's
// own, which takes emission and next-event estimation.
fn trace_photon_map_path(x: u32, y: u32, sampler: Sampler, own: bool) -> vec3<f32> {
    let max_edges = max_path_edges();
    // Step 1 - camera ray: a uniform point in the pixel (box filter) through the pinhole.
    let u_camera = draw4(sampler, DIM_CAMERA);
    var ray = camera_ray(frame.camera, x, y, u_camera.x, u_camera.y);

    var radiance = vec3<f32>(0.0);
    var throughput = vec3<f32>(1.0);
    // Product of etap^2 over refractions, for Russian roulette (as in path.wgsl).
    var eta_scale = 1.0;
    // Whether the subpath has passed x, its first diffuse point: it is then the gather ray.
    var gathering = false;
    var bounce = 0u;

    loop {
        // Step 2 - closest hit: the nearest surface along the ray over the BVH.
        let candidate = traverse(ray, F32_MAX, false);
        if !candidate.found {
            break;
        }
        let hit = surface_hit(ray, candidate);
        let material = materials[hit.material];
        let wo = -ray.d;
        let cos_o = dot(hit.n, wo);
        // Edges of the camera subpath up to this vertex.
        let depth = bounce + 1u;

        // Step 3 - emission: an emitter seen from its front by the camera, straight or through
        // mirrors and glass. Met by the gather ray, its light is x's direct or caustic light,
        // taken in steps 4 and 5.
        if own && material.kind == KIND_EMITTER && cos_o > 0.0 && !gathering && depth <= max_edges {
            radiance += throughput * material.emission;
        }
        let diffuse = is_diffuse(material);
        if material.kind == KIND_EMITTER && !diffuse {
            // A black emitter reflects nothing: the path ends here.
            break;
        }
        let u_light = draw4(sampler, dim_light(bounce));
        let u_bsdf = draw4(sampler, dim_bsdf(bounce));
        if diffuse {
            let n_facing = select(hit.n, -hit.n, cos_o < 0.0);
            let f = material.color * FRAC_1_PI;

            // Step 4 - direct light: one point on the emitters (an emitter by power, a uniform
            // point on it), one shadow ray, f · Le · cos theta / p_omega.
            let ls = sample_emitter(u_light.x, u_light.y, u_light.z);
            if own && depth < max_edges {
                let link = link_to_emitter(hit.p, hit.p_err, hit.n, n_facing, ls);
                if link.found && !occluded(link.shadow, 1.0) {
                    radiance += throughput * f * link.le * (link.cos_s / link.light_pdf);
                }
            }

            // Step 5 - the photon maps: at x the caustic map; at y, the gather ray's end, the
            // caustic and the global map (all the light that has scattered since it left the
            // light, direct light apart). Then the subpath ends at y.
            let map = select(PHOTON_MAP_CAUSTIC, PHOTON_MAP_CAUSTIC_AND_GLOBAL, gathering);
            radiance += throughput * f * density(hit.p, n_facing, depth, map);
            if gathering {
                break;
            }
            gathering = true;
        }

        // Step 6 - scattering: at x the gather ray, a cosine-distributed direction (weight rho);
        // at mirrors and glass the specular bounce.
        let bs = sample_bsdf(material, hit.n, wo, u_bsdf, TRANSPORT_RADIANCE);
        throughput *= bs.weight;
        if bs.pdf == 0.0 {
            throughput *= frame.specular_scale;
        }
        eta_scale *= bs.eta2;
        if max_element(throughput) <= 0.0 || depth >= max_edges {
            break;
        }
        ray = Ray(offset_ray_origin(hit.p, hit.p_err, hit.n, bs.wi), bs.wi);

        // Step 7 - Russian roulette, as in path.wgsl: from bounce RR_START_BOUNCE on, continue
        // with probability q = min(max(throughput) · eta_scale, 0.95) and divide by q (it ends
        // the long chains of mirrors and glass).
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

// One invocation per pixel of the dispatch's tile, for one iteration: the pixel's n_c camera
// samples, each gathering from the photon maps of this wave. Their radiance waits in
// `camera_radiance` for the resolve pass (as BDPT's camera_pass leaves it): stored by the pixel's
// first camera pass of the iteration, added to by the later waves. If the wave's photons
// overflowed the pool, the resolve pass drops the iteration and the host traces it again.
@compute @workgroup_size(8, 8, 1)
fn photon_map_pass(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
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
    // The pixel's n_c camera samples, averaged; the k-th draws the streams of pixel
    // index + k w h, as BDPT's camera subpaths do.
    let n_c = camera_radiance[band_index(index)].w;
    let path = index % frame.n_light_paths;
    let own = path >= frame.path_origin && path - frame.path_origin < frame.path_count;
    let pixels = frame.camera.width * frame.camera.height;
    var radiance = vec3<f32>(0.0);
    for (var k = 0u; k < u32(n_c); k++) {
        let sampler = frame_sampler(index + k * pixels, frame.first_sample);
        radiance += trace_photon_map_path(x, y, sampler, own);
    }
    var before = vec3<f32>(0.0);
    if frame.path_origin > 0u {
        before = camera_radiance[band_index(index)].xyz;
    }
    camera_radiance[band_index(index)] = vec4<f32>(before + radiance / n_c, n_c);
}
