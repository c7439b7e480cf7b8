// The merge radius at a camera vertex (`src/transport/merging.rs`, the same steps): the
// iteration's radius, limited by the clearance (`clearance.wgsl`).

// The merge radius at a camera vertex p on primitive prim (`merging::local_radius`): its
// clearance, at most radius and at least frame.clearance_floor of it.
fn local_radius(p: vec3<f32>, prim: u32, radius: f32) -> f32 {
    return max(clearance(p, prim, radius), frame.clearance_floor * radius);
}

// The merge radius at a camera vertex p on primitive prim as a share of the iteration's
// (`merging::merge_share`): local_radius / frame.merge_radius where the method merges within
// the clearance, else 1. Every strategy of a path through the vertex weighs the merge there with
// this radius (subpath.rs, "A radius of the vertex").
fn merge_share(p: vec3<f32>, prim: u32) -> f32 {
    if frame.merges_within_clearance == 0u {
        return 1.0;
    }
    // Where the clearance reaches the radius the share is 1 exactly: WGSL's division need not
    // give r / r = 1.
    let local = local_radius(p, prim, frame.merge_radius);
    if local >= frame.merge_radius {
        return 1.0;
    }
    return local / frame.merge_radius;
}
