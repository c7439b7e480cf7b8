// The scene arrays as read-only storage buffers: any size. Primitive references are packed four
// to a vec4<u32> so that both residencies share one access (`prim_ref` in bvh.wgsl).

@group(0) @binding(0) var<storage, read> triangles: array<Triangle>;
@group(0) @binding(1) var<storage, read> spheres: array<Sphere>;
@group(0) @binding(2) var<storage, read> materials: array<Material>;
@group(0) @binding(3) var<storage, read> emitters: array<Emitter>;
@group(0) @binding(4) var<storage, read> nodes: array<BvhNode>;
@group(0) @binding(5) var<storage, read> prims: array<vec4<u32>>;
