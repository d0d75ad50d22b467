//! # oslf-shading: each piece of shading maths once in Rust and once in WGSL
//!
//! The bake's path tracer, the ground truth, the GPU bake, the runtime's shader, its CPU
//! reference and the split-sum prefilter all evaluate the same microfacet and colour formulas.
//! They are written here, once in Rust and once in WGSL, and every path calls these: a change
//! is one edit per language, and the parity tests compare one Rust source with one WGSL source.
//!
//! | module | Rust | WGSL ([`wgsl`]) |
//! | --- | --- | --- |
//! | [`ggx`] | Trowbridge–Reitz `D`, Smith `G₁` and `V`, visible-normal sampling, glTF's `α` floor and dielectric `F₀` | `ggx.wgsl`: `ggx_distribution`, `ggx_smith_g1`, … |
//! | [`fresnel`] | Schlick's approximation (thesis Eq. 5.7) | `fresnel.wgsl`: `fresnel_schlick`, `fresnel_schlick_weight` |
//! | [`random`] | PCG32, the stream hash, stratified samples | `random.wgsl`: the same streams bit for bit (`rng_new`, `rng_f32`, `hash4`) |
//! | [`warp`] | disc, cosine-hemisphere and sphere warps with densities and inverses; the frame about a normal | `warp.wgsl`: the warps and the frame |
//! | [`sh`] | spherical harmonics of bands 0–2: the basis, zonal convolution (the cosine and Ashikhmin–Shirley diffuse lobes), the diffuse base's Fresnel share | `sh.wgsl`: `sh_basis`, `sh_convolve`, … |
//! | [`color`] | the sRGB transfer functions, the ACES tone curve, luminance | `color.wgsl`: `srgb_to_linear`, `linear_to_srgb`, `aces`, `luminance` |
//!
//! Each WGSL function is the Rust function of the same module with the module's name as a
//! prefix (`ggx::distribution` is `ggx_distribution`), the same operations in the same order,
//! so that the two agree to the last bit where the GPU rounds as the CPU does. The WGSL files are
//! modules that shaders import (`import package::shading::ggx::{ggx_distribution};`,
//! [`wgsl::modules`]); assembled shaders keep every name as written, and the prefixes keep
//! them apart from the shaders' own.
//!
//! It depends on glam alone (and, with the feature `assemble` that the crates' tests use, on the
//! `wesl` module system): no I/O, no GPU, no other oslf crate. Every oslf crate that
//! shades may depend on it; it must never depend on any of them.

pub mod color;
pub mod fresnel;
pub mod ggx;
pub mod random;
pub mod sh;
pub mod warp;
pub mod wgsl;
