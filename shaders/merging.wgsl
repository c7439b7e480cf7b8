// The merge radius at a camera vertex (`src/transport/merging.rs`, the same steps): a share of
// the iteration's largest radius by the vertex's distance from the eye, limited by the
// clearance (`clearance.wgsl`).

// The least share of the largest radius that footprint_share gives (`merging::FOOTPRINT_FLOOR`).
const FOOTPRINT_FLOOR: f32 = 0.01;

// A camera vertex's share of the iteration's largest radius by its distance t along the camera
// subpath (`merging::footprint_share`): min(t / frame.merge_reach, 1), at least FOOTPRINT_FLOOR;
// 1 where the radius is uniform (reach 0).
fn footprint_share(t: f32) -> f32 {
    if frame.merge_reach <= 0.0 {
        return 1.0;
    }
    return min(max(t / frame.merge_reach, FOOTPRINT_FLOOR), 1.0);
}

// The merge radius at a camera vertex p on primitive prim (`merging::local_radius`): its
// clearance, at most radius and at least frame.clearance_floor of it.
fn local_radius(p: vec3<f32>, prim: u32, radius: f32) -> f32 {
    return max(clearance(p, prim, radius), frame.clearance_floor * radius);
}

// The merge radius at a camera vertex p on primitive prim as a share of the iteration's largest
// (`merging::merge_share`): the vertex's footprint of it, limited by the clearance where the
// method merges within it. Every strategy of a path through the vertex weighs the merge there
// with this radius (subpath.rs, "A radius of the vertex").
fn merge_share(p: vec3<f32>, prim: u32, footprint: f32) -> f32 {
    if frame.merges_within_clearance == 0u {
        return footprint;
    }
    let own = footprint * frame.merge_radius;
    // Where the clearance reaches the radius the share is the footprint exactly: WGSL's
    // division need not give r / r = 1.
    let local = local_radius(p, prim, own);
    if local >= own {
        return footprint;
    }
    return local / frame.merge_radius;
}
