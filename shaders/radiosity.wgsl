// Radiosity: `src/cpu/radiosity.rs` again, with the same names, the same steps in the same
// order and the same step comments. The patch table (`PatchGrid`, `Patch`) is laid out on the
// host (`src/transport/patches.rs`); the host side of these kernels is `src/gpu/radiosity.rs`.
// The solution is in radiance units: L_i = Le_i + ρ_i Σ_j F_ij L_j.

// The dimension block of the form-factor rays (`DIM_FORM_FACTOR`): point (2), direction (2).
const DIM_FORM_FACTOR: u32 = 0x30000000u;

// Where one primitive's patches are (`PatchGrid`): first patch (or NO_PATCHES), the grid (a
// triangle's n twice, a sphere's n_z and n_φ), sides per cell.
struct PatchGrid {
    first: u32,
    n: u32,
    m: u32,
    sides: u32,
}

// One patch (`Patch`): reflectance, emission (front side of an emitter only), primitive, cell,
// side and area.
struct Patch {
    albedo: vec3<f32>,
    prim: u32,
    emission: vec3<f32>,
    cell: u32,
    side: u32,
    area: f32,
    pad0: u32,
    pad1: u32,
}

// One dispatch of the solve (`RadiosityParams` in src/gpu/radiosity.rs).
struct RadiosityParams {
    patch_count: u32,
    rays_per_patch: u32,
    first_ray: u32,
    ray_count: u32,
    seed: u32,
    triangle_count: u32,
    // Offsets in `radiosity` of the step's input and output (0 or patch_count), and of the
    // indirect light (2 patch_count).
    step_input: u32,
    step_output: u32,
    // Test-only faults (`Faults::form_factor_scale`, `form_factor_uniform_directions`,
    // `indirect_with_direct`).
    form_factor_scale: f32,
    uniform_directions: u32,
    indirect_with_direct: u32,
    pad0: u32,
}

const NO_PATCHES: u32 = 0xffffffffu;

// Group 2 (group 1 is the light-subpath methods'; radiosity's pipelines leave it empty).
// The parameters as a read-only storage buffer, not a uniform one: with an eighth uniform buffer
// beside the seven of the uniform residency (scene arrays and frame), lavapipe (Mesa 22.3)
// corrupted its heap when the pipelines were destroyed.
@group(2) @binding(0) var<storage, read> radiosity_params: RadiosityParams;
@group(2) @binding(1) var<storage, read> patch_grids: array<PatchGrid>;
@group(2) @binding(2) var<storage, read> patches: array<Patch>;
// F, row-major N x N.
@group(2) @binding(3) var<storage, read_write> form_factors: array<f32>;
// L of two Jacobi steps (ping-pong, N each), then each patch's indirect light (N).
@group(2) @binding(4) var<storage, read_write> radiosity: array<vec4<f32>>;

// The grid of primitive prim (a `prims` reference).
fn patch_grid(prim: u32) -> PatchGrid {
    if (prim & PRIM_SPHERE_BIT) != 0u {
        return patch_grids[radiosity_params.triangle_count + (prim & ~PRIM_SPHERE_BIT)];
    }
    return patch_grids[prim];
}

// The cell of an n x n barycentric grid that holds (b1, b2), clamped into the triangle
// (`triangle_cell` in src/transport/patches.rs).
fn triangle_cell(n: u32, b1: f32, b2: f32) -> u32 {
    let nf = f32(n);
    let x = max(b1 * nf, 0.0);
    let y = max(b2 * nf, 0.0);
    let i = min(u32(x), n - 1u);
    let j = min(u32(y), n - 1u - i);
    let upper = select(0u, 1u, x - f32(i) + (y - f32(j)) >= 1.0 && i + j < n - 1u);
    return i * (2u * n - i) + 2u * j + upper;
}

// A cell's corner the edges leave from, and the two edges, in barycentrics
// (`triangle_cell_corners`).
struct CellCorners {
    c: vec2<f32>,
    e1: vec2<f32>,
    e2: vec2<f32>,
}

fn triangle_cell_corners(n: u32, cell: u32) -> CellCorners {
    // Row i holds cells i (2n - i) .. (i + 1)(2n - i - 1).
    var i = 0u;
    while (i + 1u) * (2u * n - i - 1u) <= cell {
        i += 1u;
    }
    let k = cell - i * (2u * n - i);
    let j = k / 2u;
    let upper = k % 2u;
    let h = 1.0 / f32(n);
    let x = f32(i) * h;
    let y = f32(j) * h;
    if upper == 0u {
        return CellCorners(vec2<f32>(x, y), vec2<f32>(h, 0.0), vec2<f32>(0.0, h));
    }
    return CellCorners(vec2<f32>(x + h, y + h), vec2<f32>(-h, 0.0), vec2<f32>(0.0, -h));
}

// The barycentrics (b1, b2) of a point p in (or next to) a triangle's plane.
fn barycentrics(tri: Triangle, p: vec3<f32>) -> vec2<f32> {
    let e1 = tri.v1 - tri.v0;
    let e2 = tri.v2 - tri.v0;
    let d = p - tri.v0;
    let n = cross(e1, e2);
    let inv = 1.0 / dot(n, n);
    return vec2<f32>(dot(cross(d, e2), n) * inv, dot(cross(e1, d), n) * inv);
}

// The cell of a sphere's n_z x n_φ grid that holds the unit direction d from its centre.
fn sphere_cell(n: u32, m: u32, d: vec3<f32>) -> u32 {
    let band = min(u32(max((1.0 - d.z) * 0.5 * f32(n), 0.0)), n - 1u);
    var turns = atan2(d.y, d.x) * (0.5 * FRAC_1_PI);
    if turns < 0.0 {
        turns += 1.0;
    }
    let sector = min(u32(max(turns * f32(m), 0.0)), m - 1u);
    return band * m + sector;
}

// The patch of the point p on primitive prim, seen from the back or the front of a triangle.
fn patch_of(prim: u32, p: vec3<f32>, back: bool) -> u32 {
    let grid = patch_grid(prim);
    var cell: u32;
    if (prim & PRIM_SPHERE_BIT) != 0u {
        let s = spheres[prim & ~PRIM_SPHERE_BIT];
        cell = sphere_cell(grid.n, grid.m, (p - s.center) / s.radius);
    } else {
        let b = barycentrics(triangles[prim], p);
        cell = triangle_cell(grid.n, b.x, b.y);
    }
    return grid.first + cell * grid.sides + min(select(0u, 1u, back), grid.sides - 1u);
}

// A point on a patch, uniform over its area, with its error bound and its side's normal.
struct PatchPoint {
    p: vec3<f32>,
    p_err: vec3<f32>,
    n: vec3<f32>,
}

fn patch_point(pt: Patch, u1: f32, u2: f32) -> PatchPoint {
    let grid = patch_grid(pt.prim);
    if (pt.prim & PRIM_SPHERE_BIT) != 0u {
        let s = spheres[pt.prim & ~PRIM_SPHERE_BIT];
        // z uniform within the band, φ within the sector: uniform in area (Archimedes).
        let band = pt.cell / grid.m;
        let sector = pt.cell % grid.m;
        let z = 1.0 - 2.0 * (f32(band) + u1) / f32(grid.n);
        let r = sqrt(max(1.0 - z * z, 0.0));
        let sc = sin_cos_turns((f32(sector) + u2) / f32(grid.m));
        let d = vec3<f32>(r * sc.y, r * sc.x, z);
        let pe = sphere_point_at(s, s.radius * d);
        return PatchPoint(pe.p, pe.p_err, sphere_normal(s, d));
    }
    let tri = triangles[pt.prim];
    let cc = triangle_cell_corners(grid.n, pt.cell);
    let st = sample_uniform_triangle(u1, u2);
    let b1 = cc.c.x + st.y * cc.e1.x + st.z * cc.e2.x;
    let b2 = cc.c.y + st.y * cc.e1.y + st.z * cc.e2.y;
    let pe = triangle_hit_point(tri, b1, b2);
    return PatchPoint(pe.p, pe.p_err, select(tri.n, -tri.n, pt.side != 0u));
}

// The largest relative change of a channel between two steps (0 where both are 0); the host
// takes it from the two steps read back (`relative_change`).

// One invocation per patch i: rays first_ray .. first_ray + ray_count of row i of the form
// factors (`form_factor_row`), added to the row.
@compute @workgroup_size(64, 1, 1)
fn form_factor_rows(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    let n_patches = radiosity_params.patch_count;
    if i >= n_patches {
        return;
    }
    // Step 1 - form factors: R rays from uniform points on patch i, cosine-distributed about
    // its side; the patch each first meets gets 1 / R (mirrors, glass and misses lose theirs).
    let pt = patches[i];
    let weight = radiosity_params.form_factor_scale / f32(radiosity_params.rays_per_patch);
    let row = i * n_patches;
    for (var r = radiosity_params.first_ray; r < radiosity_params.first_ray + radiosity_params.ray_count; r++) {
        let u = draw4(Sampler(radiosity_params.seed, i, r, SAMPLER_INDEPENDENT), DIM_FORM_FACTOR);
        let pp = patch_point(pt, u.x, u.y);
        var local: vec3<f32>;
        if radiosity_params.uniform_directions != 0u {
            let d = sample_uniform_sphere(u.z, u.w);
            local = vec3<f32>(d.x, d.y, abs(d.z));
        } else {
            local = sample_cosine_hemisphere(u.z, u.w);
        }
        let basis = orthonormal_basis(pp.n);
        let d = local.x * basis.t + local.y * basis.b + local.z * pp.n;
        let ray = Ray(offset_ray_origin(pp.p, pp.p_err, pp.n, d), d);
        let candidate = traverse(ray, F32_MAX, false);
        if !candidate.found {
            continue;
        }
        let hit = surface_hit(ray, candidate);
        let kind = materials[hit.material].kind;
        if kind == KIND_MIRROR || kind == KIND_GLASS {
            continue;
        }
        let j = patch_of(hit.prim, hit.p, dot(hit.n, d) > 0.0);
        form_factors[row + j] += weight;
    }
}

// One invocation per patch i: one Jacobi step from radiosity[step_input..] into radiosity[step_output..].
@compute @workgroup_size(64, 1, 1)
fn jacobi_step(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    let n_patches = radiosity_params.patch_count;
    if i >= n_patches {
        return;
    }
    // Step 2 - Jacobi: L_i = Le_i + ρ_i Σ_j F_ij L_j from the previous step's L.
    let row = i * n_patches;
    var sum = vec3<f32>(0.0);
    for (var j = 0u; j < n_patches; j++) {
        sum += form_factors[row + j] * radiosity[radiosity_params.step_input + j].xyz;
    }
    let pt = patches[i];
    radiosity[radiosity_params.step_output + i] = vec4<f32>(pt.emission + pt.albedo * sum, 0.0);
}

// One invocation per patch i: its indirect light from the solution at radiosity[step_input..],
// into radiosity[2N + i].
@compute @workgroup_size(64, 1, 1)
fn gather_indirect(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    let n_patches = radiosity_params.patch_count;
    if i >= n_patches {
        return;
    }
    // Step 3 - indirect light: what reaches patch i from the other patches but their
    // emission (next-event estimation takes that), reflected: ρ_i Σ_j F_ij (L_j − Le_j).
    let row = i * n_patches;
    var sum = vec3<f32>(0.0);
    for (var j = 0u; j < n_patches; j++) {
        var emitted = patches[j].emission;
        if radiosity_params.indirect_with_direct != 0u {
            emitted = vec3<f32>(0.0);
        }
        sum += form_factors[row + j] * (radiosity[radiosity_params.step_input + j].xyz - emitted);
    }
    radiosity[2u * n_patches + i] = vec4<f32>(patches[i].albedo * sum, 0.0);
}

// One ray of the tree, as Whitted's.
struct RadiosityBranch {
    ray: Ray,
    weight: vec3<f32>,
    depth: u32,
}

// The radiance arriving at pixel (x, y) along one camera sample's ray tree, with the solution's
// indirect light at each diffuse surface.
fn trace_radiosity(x: u32, y: u32, sampler: Sampler) -> vec3<f32> {
    // Step 4 - the image: Whitted's ray tree (camera ray, then both branches at glass, to
    // WHITTED_MAX_DEPTH specular bounces), walked depth first in the same order.
    let u_camera = draw4(sampler, DIM_CAMERA);
    var stack: array<RadiosityBranch, WHITTED_MAX_DEPTH + 1u>;
    stack[0] = RadiosityBranch(camera_ray(frame.camera, x, y, u_camera.x, u_camera.y), vec3<f32>(1.0), 0u);
    var size = 1u;
    var radiance = vec3<f32>(0.0);
    var branch = 0u;
    let indirect_offset = 2u * radiosity_params.patch_count;
    while size > 0u {
        size -= 1u;
        let b = stack[size];
        let index = branch;
        branch += 1u;

        // Step 4a - closest hit: the nearest surface along the ray; a miss sees nothing.
        let candidate = traverse(b.ray, F32_MAX, false);
        if !candidate.found {
            continue;
        }
        let hit = surface_hit(b.ray, candidate);
        let material = materials[hit.material];
        let wo = -b.ray.d;
        let cos_o = dot(hit.n, wo);

        // Step 4b - emission: an emitter seen from its front, straight or in mirrors and glass.
        if material.kind == KIND_EMITTER && cos_o > 0.0 {
            radiance += b.weight * material.emission;
        }

        // Step 4c - diffuse surfaces: direct light by one point on the emitters and one shadow
        // ray (f · Le · cos θs / p_ω), plus the indirect light of the patch seen, from its side.
        // The branch ends here.
        if is_diffuse(material) {
            let u = draw4(sampler, dim_light(index));
            let n_facing = select(hit.n, -hit.n, cos_o < 0.0);
            let ls = sample_emitter(u.x, u.y, u.z);
            let link = link_to_emitter(hit.p, hit.p_err, hit.n, n_facing, ls);
            if link.found && !occluded(link.shadow, 1.0) {
                let f = material.color * FRAC_1_PI;
                radiance += b.weight * f * link.le * (link.cos_s / link.light_pdf);
            }
            let pt = patch_of(hit.prim, hit.p, cos_o < 0.0);
            radiance += b.weight * radiosity[indirect_offset + pt].xyz;
            continue;
        }

        // Step 4d - perfect specular, as Whitted's: a mirror reflects with its reflectance;
        // glass reflects with F and refracts with (1 - F) · tint / η², both followed (the
        // refraction first). A black emitter ends the branch.
        if b.depth >= WHITTED_MAX_DEPTH {
            continue;
        }
        let weight = b.weight * frame.specular_scale;
        let reflected = reflect_about(wo, hit.n);
        if material.kind == KIND_MIRROR {
            let w = weight * material.color;
            if max_element(w) > 0.0 {
                stack[size] = RadiosityBranch(Ray(offset_ray_origin(hit.p, hit.p_err, hit.n, reflected), reflected), w, b.depth + 1u);
                size += 1u;
            }
        } else if material.kind == KIND_GLASS {
            let f = fresnel_dielectric(cos_o, material.ior);
            let w = weight * f;
            if max_element(w) > 0.0 {
                stack[size] = RadiosityBranch(Ray(offset_ray_origin(hit.p, hit.p_err, hit.n, reflected), reflected), w, b.depth + 1u);
                size += 1u;
            }
            let r = refract_through(wo, hit.n, material.ior);
            if r.possible {
                let wt = weight * (1.0 - f) * material.color / (r.etap * r.etap);
                if max_element(wt) > 0.0 {
                    stack[size] = RadiosityBranch(Ray(offset_ray_origin(hit.p, hit.p_err, hit.n, r.wt), r.wt), wt, b.depth + 1u);
                    size += 1u;
                }
            }
        }
    }
    return radiance;
}

// One invocation per pixel of the dispatch's tile: the frame's samples of that pixel, added to
// the pass's sums, as `whitted_pass` adds Whitted's.
@compute @workgroup_size(8, 8, 1)
fn radiosity_pass(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.tile_size.x || gid.y >= frame.tile_size.y || frame.sample_count == 0u {
        return;
    }
    let x = frame.tile_origin.x + gid.x;
    let y = frame.tile_origin.y + gid.y;
    let index = y * frame.camera.width + x;
    var sums = PixelSums();
    for (var s = frame.first_sample; s < frame.first_sample + frame.sample_count; s++) {
        add_sample(&sums, s, trace_radiosity(x, y, frame_sampler(index, s)));
    }
    add_to_pixel(x, y, sums);
}
