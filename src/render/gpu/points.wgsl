// Points as screen-space squares (a point primitive is one pixel wide on WebGPU).
//
// Three vertices (one triangle around the point's square) per point, with no vertex buffers:
// vertex i belongs to point i / 3 and is corner i % 3 of its triangle, and the point's data is
// fetched from two textures ("vertex pulling"); the fragment shader drops the pixels of the
// triangle outside the square. See src/render/gpu/points.rs for why (software renderers run
// per-point instancing as one small draw per point, and pay per triangle).
//
// The vertex shader places the point at X + t·(X' − X) (the morph between frame 1 and frame 2),
// projects it, and moves each corner by the point size in drawing-buffer pixels, so points keep
// their pixel size at any depth. Depth comes from the point's centre: the nearest point wins,
// whatever the draw order.
//
// Colours are sRGB bytes (an rgba8unorm texture). `fs_plain` writes them unchanged (for non-sRGB
// targets); `fs_srgb` converts them to linear first, because an sRGB target encodes what it gets.

struct Uniforms {
    view_projection: mat4x4<f32>, // world (camera 1's frame) → clip
    viewport_px: vec2<f32>,       // drawing-buffer size in pixels
    point_size_px: f32,           // side of a point's square in pixels
    morph: f32,                   // t in [0, 1]
}

@group(0) @binding(0) var<uniform> u: Uniforms;
// Two texels per point, row by row: X then X' (xyz; w unused).
@group(0) @binding(1) var positions: texture_2d<f32>;
// Two texels per point, in the same places: the frame-1 colour then the frame-2 colour.
@group(0) @binding(2) var colours: texture_2d<f32>;

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) colour: vec4<f32>,
    // Position in the point's square, in half sides: the square is [−1, 1)².
    @location(1) local: vec2<f32>,
}

// Where texel `index` lies in a texture `width` texels wide.
fn texel(index: u32, width: u32) -> vec2<i32> {
    return vec2<i32>(i32(index % width), i32(index / width));
}

@vertex
fn vs_main(@builtin(vertex_index) vertex: u32) -> VertexOut {
    let point = vertex / 3u;
    let corner = vertex % 3u;
    let width = textureDimensions(positions).x;
    let first = texel(2u * point, width);
    let second = texel(2u * point + 1u, width);

    let world = mix(textureLoad(positions, first, 0).xyz, textureLoad(positions, second, 0).xyz, u.morph);
    let centre = u.view_projection * vec4<f32>(world, 1.0);
    // One triangle around the square [−1, 1]²: (−1, −1), (3, −1), (−1, 3); the fragment shader
    // drops what lies outside the square.
    let side = vec2<f32>(select(-1.0, 3.0, corner == 1u), select(-1.0, 3.0, corner == 2u));
    // Half a point in NDC is point_size_px / viewport_px; scaled by w to undo the perspective divide.
    let offset = side * (u.point_size_px / u.viewport_px) * centre.w;

    var out: VertexOut;
    out.clip = vec4<f32>(centre.xy + offset, centre.z, centre.w);
    out.colour = mix(textureLoad(colours, first, 0), textureLoad(colours, second, 0), u.morph);
    // NDC y points up, pixel rows down: flip y so that "local" runs like pixels.
    out.local = vec2<f32>(side.x, -side.y);
    return out;
}

// Keeps the pixels whose centres lie in the half-open square [−1, 1)² (so a point of an even
// size in pixels covers exactly that many pixels even when its edges pass through pixel centres).
fn in_square(local: vec2<f32>) -> bool {
    return all(local >= vec2<f32>(-1.0)) && all(local < vec2<f32>(1.0));
}

@fragment
fn fs_plain(in: VertexOut) -> @location(0) vec4<f32> {
    if !in_square(in.local) {
        discard;
    }
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
    if !in_square(in.local) {
        discard;
    }
    return vec4<f32>(srgb_to_linear(in.colour.rgb), 1.0);
}
