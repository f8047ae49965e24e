// Points as instanced screen-space quads (a point primitive is one pixel wide on WebGPU).
//
// One instance per point, four vertices per instance (a triangle strip). The vertex shader places
// the point at X + t·(X' − X) (the morph between frame 1 and frame 2), projects it, and moves each
// corner by half the point size in drawing-buffer pixels, so points keep their pixel size at any
// depth. Depth comes from the point's centre: the nearest point wins, whatever the draw order.
//
// Colours arrive as sRGB bytes (unorm8x4). `fs_plain` writes them unchanged (for non-sRGB
// targets); `fs_srgb` converts them to linear first, because an sRGB target encodes what it gets.

struct Uniforms {
    view_projection: mat4x4<f32>, // world (camera 1's frame) → clip
    viewport_px: vec2<f32>,       // drawing-buffer size in pixels
    point_size_px: f32,           // side of a point's square in pixels
    morph: f32,                   // t in [0, 1]
}

@group(0) @binding(0) var<uniform> u: Uniforms;

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) colour: vec4<f32>,
}

@vertex
fn vs_main(
    @builtin(vertex_index) corner: u32,
    @location(0) position1: vec3<f32>,
    @location(1) position2: vec3<f32>,
    @location(2) colour1: vec4<f32>,
    @location(3) colour2: vec4<f32>,
) -> VertexOut {
    let world = mix(position1, position2, u.morph);
    let centre = u.view_projection * vec4<f32>(world, 1.0);
    // Corners 0..3 of the strip: (−1, −1), (1, −1), (−1, 1), (1, 1).
    let side = vec2<f32>(f32(corner & 1u), f32(corner >> 1u)) * 2.0 - 1.0;
    // Half a point in NDC is point_size_px / viewport_px; scaled by w to undo the perspective divide.
    let offset = side * (u.point_size_px / u.viewport_px) * centre.w;
    var out: VertexOut;
    out.clip = vec4<f32>(centre.xy + offset, centre.z, centre.w);
    out.colour = mix(colour1, colour2, u.morph);
    return out;
}

@fragment
fn fs_plain(in: VertexOut) -> @location(0) vec4<f32> {
    return vec4<f32>(in.colour.rgb, 1.0);
}

// The sRGB transfer function, inverted (IEC 61966-2-1).
fn srgb_to_linear(c: vec3<f32>) -> vec3<f32> {
    let low = c / 12.92;
    let high = pow((c + 0.055) / 1.055, vec3<f32>(2.4));
    return select(high, low, c <= vec3<f32>(0.04045));
}

@fragment
fn fs_srgb(in: VertexOut) -> @location(0) vec4<f32> {
    return vec4<f32>(srgb_to_linear(in.colour.rgb), 1.0);
}
