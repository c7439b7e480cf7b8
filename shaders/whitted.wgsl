// Whitted ray tracing: `src/cpu/whitted.rs` again, with the same names, the same steps in the
// same order and the same step comments. Direct light at each diffuse surface the camera sees,
// and perfect reflection and refraction at mirrors and glass, both followed where glass splits a
// ray, to at most WHITTED_MAX_DEPTH specular bounces; no indirect diffuse light, no caustics.
// The ray tree is walked depth first with a stack, the refraction before the reflection.

const WHITTED_MAX_DEPTH: u32 = 5u;

// One ray of the tree: where it goes, what it carries (the product of the specular weights
// before it) and how many specular bounces led to it.
struct Branch {
    ray: Ray,
    weight: vec3<f32>,
    depth: u32,
}

// The radiance arriving at pixel (x, y) along one camera sample's ray tree.
fn trace_whitted(x: u32, y: u32, sampler: Sampler) -> vec3<f32> {
    // Step 1 - camera ray: a uniform point in the pixel (box filter) through the pinhole, as
    // path tracing's.
    let u_camera = draw4(sampler, DIM_CAMERA);
    // At most one pending branch per depth and the two children of the last.
    var stack: array<Branch, WHITTED_MAX_DEPTH + 1u>;
    stack[0] = Branch(camera_ray(frame.camera, x, y, u_camera.x, u_camera.y), vec3<f32>(1.0), 0u);
    var size = 1u;
    var radiance = vec3<f32>(0.0);
    var branch = 0u;
    while size > 0u {
        size -= 1u;
        let b = stack[size];
        let index = branch;
        branch += 1u;

        // Step 2 - closest hit: the nearest surface along the ray over the BVH; a miss sees
        // nothing.
        let candidate = traverse(b.ray, F32_MAX, false);
        if !candidate.found {
            continue;
        }
        let hit = surface_hit(b.ray, candidate);
        let material = materials[hit.material];
        let wo = -b.ray.d;
        let cos_o = dot(hit.n, wo);

        // Step 3 - emission: an emitter seen from its front, straight or in mirrors and glass.
        if material.kind == KIND_EMITTER && cos_o > 0.0 {
            radiance += b.weight * material.emission;
        }

        // Step 4 - direct light at diffuse surfaces: one point on the emitters (an emitter by
        // power, a uniform point on it), one shadow ray, and f · Le · cos θs / p_ω, with p_ω the
        // point's area pdf converted to solid angle. The branch ends here.
        let diffuse = material.kind == KIND_DIFFUSE || (material.kind == KIND_EMITTER && max_element(material.color) > 0.0);
        if diffuse {
            let u = draw4(sampler, dim_light(index));
            let n_facing = select(hit.n, -hit.n, cos_o < 0.0);
            let ls = sample_emitter(u.x, u.y, u.z);
            let link = link_to_emitter(hit.p, hit.p_err, hit.n, n_facing, ls);
            if link.found && !occluded(link.shadow, 1.0) {
                let f = material.color * FRAC_1_PI;
                radiance += b.weight * f * link.le * (link.cos_s / link.light_pdf);
            }
            continue;
        }

        // Step 5 - perfect specular: a mirror reflects with its reflectance; glass reflects
        // with F and refracts with (1 - F) · tint / η², both followed (the refraction first),
        // up to WHITTED_MAX_DEPTH bounces. A black emitter ends the branch.
        if b.depth >= WHITTED_MAX_DEPTH {
            continue;
        }
        let weight = b.weight * frame.specular_scale;
        let reflected = reflect_about(wo, hit.n);
        if material.kind == KIND_MIRROR {
            let w = weight * material.color;
            if max_element(w) > 0.0 {
                stack[size] = Branch(Ray(offset_ray_origin(hit.p, hit.p_err, hit.n, reflected), reflected), w, b.depth + 1u);
                size += 1u;
            }
        } else if material.kind == KIND_GLASS {
            let f = fresnel_dielectric(cos_o, material.ior);
            let w = weight * f;
            if max_element(w) > 0.0 {
                stack[size] = Branch(Ray(offset_ray_origin(hit.p, hit.p_err, hit.n, reflected), reflected), w, b.depth + 1u);
                size += 1u;
            }
            let r = refract_through(wo, hit.n, material.ior);
            if r.possible {
                let wt = weight * (1.0 - f) * material.color / (r.etap * r.etap);
                if max_element(wt) > 0.0 {
                    stack[size] = Branch(Ray(offset_ray_origin(hit.p, hit.p_err, hit.n, r.wt), r.wt), wt, b.depth + 1u);
                    size += 1u;
                }
            }
        }
    }
    return radiance;
}

// One invocation per pixel of the dispatch's tile: the frame's samples of that pixel, added to
// the pass's sums, as `render_pass` adds path tracing's.
@compute @workgroup_size(8, 8, 1)
fn whitted_pass(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.tile_size.x || gid.y >= frame.tile_size.y || frame.sample_count == 0u {
        return;
    }
    let x = frame.tile_origin.x + gid.x;
    let y = frame.tile_origin.y + gid.y;
    let index = y * frame.camera.width + x;
    var sums = PixelSums();
    for (var s = frame.first_sample; s < frame.first_sample + frame.sample_count; s++) {
        add_sample(&sums, s, trace_whitted(x, y, frame_sampler(index, s)));
    }
    add_to_pixel(x, y, sums);
}
