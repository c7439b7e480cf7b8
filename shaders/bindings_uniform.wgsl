// The scene arrays as uniform buffers, for scenes whose arrays each fit the uniform binding limit
// (64 KiB by default). Mesa 22.3's lavapipe loads storage buffers one lane at a time and
// uniform buffers with vector gathers: tncg15_room runs 1.7x as fast there in this residency
// (docs/design/gpu.md). The host rewrites the array lengths below to the scene's.

const LEN_TRIANGLES: u32 = 1u;
const LEN_SPHERES: u32 = 1u;
const LEN_MATERIALS: u32 = 1u;
const LEN_EMITTERS: u32 = 1u;
const LEN_NODES: u32 = 1u;
const LEN_PRIMS: u32 = 1u;

@group(0) @binding(0) var<uniform> triangles: array<Triangle, LEN_TRIANGLES>;
@group(0) @binding(1) var<uniform> spheres: array<Sphere, LEN_SPHERES>;
@group(0) @binding(2) var<uniform> materials: array<Material, LEN_MATERIALS>;
@group(0) @binding(3) var<uniform> emitters: array<Emitter, LEN_EMITTERS>;
@group(0) @binding(4) var<uniform> nodes: array<BvhNode, LEN_NODES>;
@group(0) @binding(5) var<uniform> prims: array<vec4<u32>, LEN_PRIMS>;
