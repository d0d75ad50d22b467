// The twin of oslf-shading's random.rs: PCG32 and the stream hash, bit for bit, with 64-bit
// integers as vec2<u32> (x = low word, y = high word), so a GPU texel draws the CPU's numbers.

fn mul32x32(a: u32, b: u32) -> vec2<u32> {
    let a0 = a & 0xffffu;
    let a1 = a >> 16u;
    let b0 = b & 0xffffu;
    let b1 = b >> 16u;
    let p00 = a0 * b0;
    let p01 = a0 * b1;
    let p10 = a1 * b0;
    let p11 = a1 * b1;
    let mid = (p00 >> 16u) + (p01 & 0xffffu) + (p10 & 0xffffu);
    return vec2<u32>((p00 & 0xffffu) | (mid << 16u), p11 + (p01 >> 16u) + (p10 >> 16u) + (mid >> 16u));
}

fn mul64(a: vec2<u32>, b: vec2<u32>) -> vec2<u32> {
    var r = mul32x32(a.x, b.x);
    r.y = r.y + a.x * b.y + a.y * b.x;
    return r;
}

fn add64(a: vec2<u32>, b: vec2<u32>) -> vec2<u32> {
    let lo = a.x + b.x;
    return vec2<u32>(lo, a.y + b.y + select(0u, 1u, lo < a.x));
}

// a >> n for 0 < n < 32.
fn shr64(a: vec2<u32>, n: u32) -> vec2<u32> {
    return vec2<u32>((a.x >> n) | (a.y << (32u - n)), a.y >> n);
}

// SplitMix64's finaliser (`mix64`).
fn mix64(z0: vec2<u32>) -> vec2<u32> {
    var z = z0;
    z = mul64(z ^ shr64(z, 30u), vec2<u32>(0x1ce4e5b9u, 0xbf58476du));
    z = mul64(z ^ shr64(z, 27u), vec2<u32>(0x133111ebu, 0x94d049bbu));
    return z ^ shr64(z, 31u);
}

const GOLDEN: vec2<u32> = vec2<u32>(0x7f4a7c15u, 0x9e3779b9u);

// `hash_u64(&[a, b, c, d])`.
fn hash4(a: vec2<u32>, b: vec2<u32>, c: vec2<u32>, d: vec2<u32>) -> vec2<u32> {
    var h = mix64(GOLDEN ^ vec2<u32>(4u, 0u));
    h = mix64(h ^ mix64(add64(a, GOLDEN)));
    h = mix64(h ^ mix64(add64(b, GOLDEN)));
    h = mix64(h ^ mix64(add64(c, GOLDEN)));
    h = mix64(h ^ mix64(add64(d, GOLDEN)));
    return h;
}

struct Rng {
    state: vec2<u32>,
    inc: vec2<u32>,
}

const PCG_MULT: vec2<u32> = vec2<u32>(0x4c957f2du, 0x5851f42du);

fn rng_next_u32(rng: ptr<function, Rng>) -> u32 {
    let old = (*rng).state;
    (*rng).state = add64(mul64(old, PCG_MULT), (*rng).inc);
    let xorshifted = shr64(shr64(old, 18u) ^ old, 27u).x;
    let rot = old.y >> 27u;
    return (xorshifted >> rot) | (xorshifted << ((32u - rot) & 31u));
}

fn rng_new(seed: vec2<u32>, stream: vec2<u32>) -> Rng {
    var rng = Rng(vec2<u32>(0u, 0u), vec2<u32>((stream.x << 1u) | 1u, (stream.y << 1u) | (stream.x >> 31u)));
    rng_next_u32(&rng);
    rng.state = add64(rng.state, seed);
    rng_next_u32(&rng);
    return rng;
}

fn rng_f32(rng: ptr<function, Rng>) -> f32 {
    return f32(rng_next_u32(rng) >> 8u) * (1.0 / 16777216.0);
}

fn rng_vec2(rng: ptr<function, Rng>) -> vec2<f32> {
    let x = rng_f32(rng);
    let y = rng_f32(rng);
    return vec2<f32>(x, y);
}
