// The scene arrays as textures of 32-bit words, read with textureLoad: any scene whose arrays
// fit the device's largest texture. The host lays each array out in order, 16 bytes a texel, in
// rows of 2^TEXEL_ROW_SHIFT texels (`gpu::pipeline::texels` in texture_residency.patch).

@group(0) @binding(0) var triangle_texels: texture_2d<u32>;
@group(0) @binding(1) var sphere_texels: texture_2d<u32>;
@group(0) @binding(2) var material_texels: texture_2d<u32>;
@group(0) @binding(3) var emitter_texels: texture_2d<u32>;
@group(0) @binding(4) var node_texels: texture_2d<u32>;
@group(0) @binding(5) var prim_texels: texture_2d<u32>;

const TEXEL_ROW_SHIFT: u32 = 12u;

fn texel(t: texture_2d<u32>, i: u32) -> vec4<u32> {
    let row_mask = (1u << TEXEL_ROW_SHIFT) - 1u;
    return textureLoad(t, vec2<u32>(i & row_mask, i >> TEXEL_ROW_SHIFT), 0);
}

fn scene_triangle(i: u32) -> Triangle {
    let w0 = texel(triangle_texels, 4u * i);
    let w1 = texel(triangle_texels, 4u * i + 1u);
    let w2 = texel(triangle_texels, 4u * i + 2u);
    let w3 = texel(triangle_texels, 4u * i + 3u);
    return Triangle(
        bitcast<vec3<f32>>(w0.xyz), w0.w,
        bitcast<vec3<f32>>(w1.xyz), w1.w,
        bitcast<vec3<f32>>(w2.xyz), w2.w,
        bitcast<vec3<f32>>(w3.xyz), w3.w,
    );
}

fn scene_sphere(i: u32) -> Sphere {
    let w0 = texel(sphere_texels, 2u * i);
    let w1 = texel(sphere_texels, 2u * i + 1u);
    return Sphere(bitcast<vec3<f32>>(w0.xyz), bitcast<f32>(w0.w), w1.x, w1.y, w1.z, w1.w);
}

fn scene_material(i: u32) -> Material {
    let w0 = texel(material_texels, 2u * i);
    let w1 = texel(material_texels, 2u * i + 1u);
    return Material(bitcast<vec3<f32>>(w0.xyz), w0.w, bitcast<vec3<f32>>(w1.xyz), bitcast<f32>(w1.w));
}

fn scene_emitter(i: u32) -> Emitter {
    let w = texel(emitter_texels, i);
    return Emitter(w.x, bitcast<f32>(w.y), bitcast<f32>(w.z), bitcast<f32>(w.w));
}

fn bvh_node(i: u32) -> BvhNode {
    let b = 8u * i;
    return BvhNode(
        bitcast<vec4<f32>>(texel(node_texels, b)),
        bitcast<vec4<f32>>(texel(node_texels, b + 1u)),
        bitcast<vec4<f32>>(texel(node_texels, b + 2u)),
        bitcast<vec4<f32>>(texel(node_texels, b + 3u)),
        bitcast<vec4<f32>>(texel(node_texels, b + 4u)),
        bitcast<vec4<f32>>(texel(node_texels, b + 5u)),
        texel(node_texels, b + 6u),
        texel(node_texels, b + 7u),
    );
}

fn prim_ref(k: u32) -> u32 {
    return texel(prim_texels, k >> 2u)[k & 3u];
}
