// Every tessellation vertex's position and unit normal (paper 003 §7.3's evaluation, as a
// compute dispatch): a vertex entry names its kind and record; the record names a patch (its
// point indices) and either a parameter on a bicubic B-spline patch or a combination (three
// rows of weights: position, ∂/∂s, ∂/∂t). Output: 6 floats per vertex, px py pz nx ny nz, the
// layout the render pass reads as its vertex buffer.

struct Params {
    // The global index of this dispatch's first vertex.
    first: u32,
    // The number of vertices.
    count: u32,
    // Invocations per row of the dispatch (workgroups along x times 64).
    stride: u32,
    pad: u32,
    // The cage's centre: points are stored relative to it.
    origin: vec4<f32>,
}

// A regular face's cell grid: vertex base + j n + i at ((i + ½)/n, (j + ½)/n).
struct Block {
    base: u32,
    rate: u32,
    points: u32,
    pad: u32,
}

// A point of a bicubic patch at (s, t), with the rows turning (∂/∂s, ∂/∂t) into (∂/∂u, ∂/∂v).
struct Bicubic {
    points: u32,
    s: f32,
    t: f32,
    pad: u32,
    ju: vec2<f32>,
    jv: vec2<f32>,
}

// A point on an exact stencil: len points, 3 rows of len weights.
struct General {
    points: u32,
    len: u32,
    weights: u32,
    pad: u32,
    ju: vec2<f32>,
    jv: vec2<f32>,
}

const KIND_SHIFT: u32 = 30u;
const KIND_BLOCK: u32 = 0u;
const KIND_BICUBIC: u32 = 1u;

@group(0) @binding(0) var<storage, read> points: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read> entries: array<u32>;
@group(0) @binding(2) var<storage, read> blocks: array<Block>;
@group(0) @binding(3) var<storage, read> bicubics: array<Bicubic>;
@group(0) @binding(4) var<storage, read> generals: array<General>;
@group(0) @binding(5) var<storage, read> patches: array<u32>;
@group(0) @binding(6) var<storage, read> weights: array<f32>;
@group(0) @binding(7) var<storage, read_write> out: array<f32>;
@group(0) @binding(8) var<uniform> params: Params;

// The uniform cubic B-spline basis and its derivative.
fn basis(t: f32) -> vec4<f32> {
    let s = 1.0 - t;
    let t2 = t * t;
    let t3 = t2 * t;
    return vec4<f32>(s * s * s, 3.0 * t3 - 6.0 * t2 + 4.0, -3.0 * t3 + 3.0 * t2 + 3.0 * t + 1.0, t3) / 6.0;
}

fn derivative(t: f32) -> vec4<f32> {
    let s = 1.0 - t;
    return vec4<f32>(-0.5 * s * s, 0.5 * (3.0 * t * t - 4.0 * t), 0.5 * (-3.0 * t * t + 2.0 * t + 1.0), 0.5 * t * t);
}

struct Point {
    p: vec3<f32>,
    ds: vec3<f32>,
    dt: vec3<f32>,
}

// The bicubic patch whose control point j·4 + i sits at (i − 1, j − 1), at (s, t); the control
// points are taken relative to the (1, 1) one, so the sums cancel less.
fn bicubic(at: u32, s: f32, t: f32) -> Point {
    let bs = basis(s);
    let ds = derivative(s);
    let bt = basis(t);
    let dt = derivative(t);
    let centre = points[patches[at + 5u]].xyz;
    var r = Point(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0));
    for (var j = 0u; j < 4u; j++) {
        var c = vec3<f32>(0.0);
        var e = vec3<f32>(0.0);
        for (var i = 0u; i < 4u; i++) {
            let x = points[patches[at + j * 4u + i]].xyz - centre;
            c += bs[i] * x;
            e += ds[i] * x;
        }
        r.p += bt[j] * c;
        r.ds += bt[j] * e;
        r.dt += dt[j] * c;
    }
    r.p += centre;
    return r;
}

// An exact stencil, relative to its first point (position weights sum to 1, derivative
// weights to 0).
fn general(g: General) -> Point {
    let first = points[patches[g.points]].xyz;
    var r = Point(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0));
    for (var i = 0u; i < g.len; i++) {
        let x = points[patches[g.points + i]].xyz - first;
        r.p += weights[g.weights + i] * x;
        r.ds += weights[g.weights + g.len + i] * x;
        r.dt += weights[g.weights + 2u * g.len + i] * x;
    }
    r.p += first;
    return r;
}

@compute @workgroup_size(64)
fn evaluate(@builtin(global_invocation_id) id: vec3<u32>) {
    let k = id.x + id.y * params.stride;
    if k >= params.count {
        return;
    }
    let entry = entries[k];
    let kind = entry >> KIND_SHIFT;
    let index = entry & ((1u << KIND_SHIFT) - 1u);
    var r: Point;
    var ju = vec2<f32>(1.0, 0.0);
    var jv = vec2<f32>(0.0, 1.0);
    if kind == KIND_BLOCK {
        let b = blocks[index];
        let local = params.first + k - b.base;
        let n = f32(b.rate);
        r = bicubic(b.points, (f32(local % b.rate) + 0.5) / n, (f32(local / b.rate) + 0.5) / n);
    } else if kind == KIND_BICUBIC {
        let b = bicubics[index];
        r = bicubic(b.points, b.s, b.t);
        ju = b.ju;
        jv = b.jv;
    } else {
        let g = generals[index];
        r = general(g);
        ju = g.ju;
        jv = g.jv;
    }
    let du = ju.x * r.ds + ju.y * r.dt;
    let dv = jv.x * r.ds + jv.y * r.dt;
    let c = cross(du, dv);
    let l = length(c);
    var n = vec3<f32>(0.0);
    if l > 0.0 {
        n = c / l;
    }
    let p = r.p + params.origin.xyz;
    let o = 6u * k;
    out[o] = p.x;
    out[o + 1u] = p.y;
    out[o + 2u] = p.z;
    out[o + 3u] = n.x;
    out[o + 4u] = n.y;
    out[o + 5u] = n.z;
}
