// Offscreen rendering of a tessellation (src/render.rs): the shaded surface from the exact
// per-vertex normals, its wireframe, and the control cage. Colours are linear; the target is
// Rgba8UnormSrgb, so the hardware encodes them.

struct Uniforms {
    view_proj: mat4x4<f32>,
    // xyz: the eye; w: the fraction of the way to the eye that lines are pulled (no z-fighting).
    eye: vec4<f32>,
    // xyz: towards the key light (unit); w: its intensity.
    key: vec4<f32>,
    // xyz: towards the fill light (unit); w: its intensity.
    fill: vec4<f32>,
    // rgb: the surface's albedo; a: the ambient term.
    surface: vec4<f32>,
    // rgb and alpha of the wireframe's lines.
    wire: vec4<f32>,
    // rgb and alpha of the cage's lines (hidden parts at a third of it).
    cage: vec4<f32>,
    // x: specular strength; y: Blinn-Phong exponent; z: the texture's repetitions per unit of
    // texture coordinates (the textured surface).
    specular: vec4<f32>,
};

@group(0) @binding(0) var<uniform> u: Uniforms;

// The textured surface's image (its pipeline only).
@group(1) @binding(0) var image: texture_2d<f32>;
@group(1) @binding(1) var image_sampler: sampler;

struct SurfaceOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
};

@vertex
fn vs_surface(@location(0) position: vec3<f32>, @location(1) normal: vec3<f32>) -> SurfaceOut {
    var out: SurfaceOut;
    out.clip = u.view_proj * vec4<f32>(position, 1.0);
    out.world = position;
    out.normal = normal;
    return out;
}

// The surface's colour at a point with albedo `albedo`, lit by the key and fill lights.
fn shade(world: vec3<f32>, normal: vec3<f32>, front: bool, albedo: vec3<f32>) -> vec4<f32> {
    // Two-sided: the inside of an open surface is lit as seen.
    var n = normalize(normal);
    if !front {
        n = -n;
    }
    let v = normalize(u.eye.xyz - world);
    let diffuse = u.key.w * max(dot(n, u.key.xyz), 0.0) + u.fill.w * max(dot(n, u.fill.xyz), 0.0);
    // A little more ambient from above the view than from below.
    let ambient = u.surface.a * (0.75 + 0.25 * dot(n, normalize(u.key.xyz + u.fill.xyz)));
    let h = normalize(u.key.xyz + v);
    let specular = u.specular.x * pow(max(dot(n, h), 0.0), u.specular.y) * select(0.0, 1.0, dot(n, u.key.xyz) > 0.0);
    let colour = albedo * (ambient + diffuse) + vec3<f32>(specular);
    return vec4<f32>(min(colour, vec3<f32>(1.0)), 1.0);
}

@fragment
fn fs_surface(in: SurfaceOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    return shade(in.world, in.normal, front, u.surface.rgb);
}

struct TexturedOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
};

@vertex
fn vs_textured(
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
) -> TexturedOut {
    var out: TexturedOut;
    out.clip = u.view_proj * vec4<f32>(position, 1.0);
    out.world = position;
    out.normal = normal;
    out.uv = uv;
    return out;
}

// The image at `(s, 1 - t) · repeat`: texture coordinates run up the image (OBJ's `vt`).
@fragment
fn fs_textured(in: TexturedOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    let albedo = textureSample(image, image_sampler, vec2<f32>(in.uv.x, 1.0 - in.uv.y) * u.specular.z).rgb;
    return shade(in.world, in.normal, front, albedo);
}

@vertex
fn vs_line(@location(0) position: vec3<f32>) -> @builtin(position) vec4<f32> {
    let pulled = position + (u.eye.xyz - position) * u.eye.w;
    return u.view_proj * vec4<f32>(pulled, 1.0);
}

@fragment
fn fs_wire() -> @location(0) vec4<f32> {
    return u.wire;
}

@fragment
fn fs_cage() -> @location(0) vec4<f32> {
    return u.cage;
}

@fragment
fn fs_cage_hidden() -> @location(0) vec4<f32> {
    return vec4<f32>(u.cage.rgb, u.cage.a / 3.0);
}
