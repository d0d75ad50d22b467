//! Flags shared by the runtime's commands (`oslf render`, `oslf view`, `oslf cache-stats`):
//! the shading, camera and background flags (clap argument groups) and their value parsers.

use std::path::Path;

use anyhow::Context as _;
use clap::Args;
use glam::Vec3;
use oslf_format::Store;
use oslf_runtime::Camera;

use oslf_runtime::{
    AshikhminShirley, Background, Blend, DiffuseSource, GlossyFilter, Lookup, Mode, MonteCarlo,
    Order, PbrMaterial, Result, RuntimeError, SampleFilter, ShadingParams, ShadingParts, Source,
};

/// The shading flags besides mode and blend (which each command takes its own way).
#[derive(Args, Clone, Debug)]
pub struct ShadingArgs {
    /// Lobe power N of the r and n blends (0 = avg) [default: 2 with depth-corrected lookups,
    /// the thesis's 4 with --no-depth].
    #[arg(short = 'N', long = "blend-n")]
    pub blend_n: Option<f32>,
    /// Where reflections come from: the OSLF's sample points, the environment-map baseline
    /// (one cube at the object's centre, by direction alone), or that cube parallax-corrected
    /// against a proxy box.
    #[arg(long, default_value = "oslf", value_parser = parse_source)]
    pub source: Source,
    /// Shorthand for `--source env`.
    #[arg(long, conflicts_with = "source")]
    pub envmap: bool,
    /// Plain lookups along the reflected direction from each sample point, as the thesis did,
    /// instead of depth-corrected ones (which need a store with a distance channel).
    #[arg(long)]
    pub no_depth: bool,
    /// How glossy samples read the cube maps: mip (filtered importance sampling) or point;
    /// split-sum is the engines' baseline of `--mode pbr` with `--source env|parallax` (the
    /// environment cube prefiltered per roughness, no Monte Carlo).
    #[arg(long, default_value = "mip", value_parser = parse_glossy_filter)]
    pub glossy_filter: GlossyFilter,
    /// The proxy box of `--source parallax`, world space: xmin,ymin,zmin,xmax,ymax,zmax
    /// [default: fitted to the environment cube's distances].
    #[arg(long, value_parser = parse_box, allow_hyphen_values = true)]
    pub proxy_box: Option<[[f32; 3]; 2]>,
    /// φ_shader in degrees (§6.3).
    #[arg(long, default_value_t = 65.0)]
    pub phi_shader: f32,
    /// Monte Carlo samples M per integration (glossy modes).
    #[arg(short = 'M', long, default_value_t = 16)]
    pub m: u32,
    /// Integration order: per-point (§5.2: integrate, then blend), per-direction (blend, then
    /// integrate), per-point-visible (per point, a hidden sample read from a point that sees it)
    /// or per-point-searched (per point, each sample read where the mirror's search meets it).
    #[arg(long, default_value = "per-point", value_parser = parse_order)]
    pub order: Order,
    /// Ashikhmin–Shirley specular reflectance R_s.
    #[arg(long, default_value_t = 1.0)]
    pub rs: f32,
    /// Ashikhmin–Shirley diffuse reflectance R_d (adds the diffuse term 5.4 when > 0).
    #[arg(long, default_value_t = 0.0)]
    pub rd: f32,
    /// Exponent n_u (along the patch's u direction).
    #[arg(long, default_value_t = 100.0)]
    pub nu: f32,
    /// Exponent n_v.
    #[arg(long, default_value_t = 100.0)]
    pub nv: f32,
    /// glTF metallic factor of the pbr mode (its base colour is the object's C_s, or its base
    /// colour texture) [default: each object's metallic-roughness material in the store, its
    /// metallic-roughness texture included, else 1]. With this flag or --roughness, every
    /// object is shaded with the flags' factors.
    #[arg(long)]
    pub metallic: Option<f32>,
    /// glTF roughness of the pbr mode (α = roughness²) [default: the object's material's,
    /// else 0.3]; see --metallic.
    #[arg(long)]
    pub roughness: Option<f32>,
    /// Seed of the Monte Carlo random numbers.
    #[arg(long, default_value_t = 0)]
    pub seed: u32,
    /// Where the glossy and pbr modes' diffuse part comes from: irradiance (what each sample
    /// point stores: its cube's spherical harmonics, smooth, no samples; a store of format 1.0
    /// has none and is sampled) or samples (M Monte Carlo lookups of the cube maps).
    #[arg(long, default_value = "irradiance", value_parser = parse_diffuse)]
    pub diffuse: DiffuseSource,
}

impl ShadingArgs {
    /// The blend's power N: the flag's, else the default for the lookups chosen.
    pub fn blend_n(&self) -> f32 {
        self.blend_n
            .unwrap_or_else(|| Lookup::default_blend_n(!self.no_depth))
    }

    /// The parameters of `mode` with `blend` and the flags that mode has (the others are
    /// not read), validated. Every flag's range is checked, whichever mode reads it; an order
    /// that reads the distance channel is refused with `--no-depth` (it would integrate per
    /// point).
    pub fn params(&self, mode: Mode, blend: Blend) -> Result<ShadingParams> {
        if self.no_depth && self.order.reads_distances() {
            return Err(RuntimeError::Parameter(format!(
                "--order {} reads the distance channel and so needs depth-corrected lookups: \
                 without them it is --order per-point; drop --no-depth or choose another order",
                self.order.name()
            )));
        }
        let defaults = PbrMaterial::default();
        ShadingParts {
            phi_shader_deg: self.phi_shader,
            lookup: Lookup::of_source(self.source(), blend, self.blend_n(), self.proxy_box),
            depth: !self.no_depth,
            lobe: AshikhminShirley {
                rs: self.rs,
                rd: self.rd,
                nu: self.nu,
                nv: self.nv,
            },
            integration: MonteCarlo {
                m: self.m,
                order: self.order,
                seed: self.seed,
                filter: match self.glossy_filter {
                    GlossyFilter::Point => SampleFilter::Point,
                    GlossyFilter::Mip | GlossyFilter::SplitSum => SampleFilter::Mip,
                },
                diffuse: self.diffuse,
            },
            material: PbrMaterial {
                metallic: self.metallic.unwrap_or(defaults.metallic),
                roughness: self.roughness.unwrap_or(defaults.roughness),
                // The store's materials unless a flag sets the factors.
                object_material: self.metallic.is_none() && self.roughness.is_none(),
            },
            split_sum: self.glossy_filter == GlossyFilter::SplitSum,
        }
        .params(mode)
    }

    /// `--source`, or `env` with `--envmap`.
    pub fn source(&self) -> Source {
        if self.envmap {
            Source::EnvMap
        } else {
            self.source
        }
    }

    /// Errors when the source needs an environment cube and `store` (at `path`) has none, or
    /// `--source parallax` has no proxy box to use.
    pub fn check_store(&self, store: &Store, path: &Path) -> Result<()> {
        let source = self.source();
        if source != Source::Oslf && store.env_cube_index().is_none() {
            return Err(RuntimeError::Parameter(format!(
                "--source {}: {} has no environment cube (bake with env_cube = true)",
                source.name(),
                path.display()
            )));
        }
        if source == Source::Parallax && self.proxy_box.is_none() && !store.header().has_distance()
        {
            return Err(RuntimeError::Parameter(format!(
                "--source parallax: {} has no distance channel to fit the proxy box to; give \
                 --proxy-box xmin,ymin,zmin,xmax,ymax,zmax",
                path.display()
            )));
        }
        Ok(())
    }
}

/// How the commands that read a store open it (`--mmap`).
#[derive(Args, Clone, Copy, Debug)]
pub struct StoreAccessArgs {
    /// Read the store through a memory map (sections and frames from the page cache, sample
    /// maps uploaded from the mapping) instead of positioned reads. Only for stores nothing
    /// overwrites in place while they are open: a store truncated under the mapping ends the
    /// process with SIGBUS, and one overwritten in place can give an image of neither
    /// version (`render` checks the file's size and modification time after the frame: a
    /// warning, an error under --strict); one replaced by rename (as oslf's writers do) is
    /// safe. See docs/store.md.
    #[arg(long, global = true)]
    pub mmap: bool,
}

impl StoreAccessArgs {
    /// Opens and validates the store at `path` as the flag says.
    pub fn open(&self, path: &std::path::Path) -> anyhow::Result<oslf_format::Store> {
        oslf_format::Store::open_with(path, self.access())
            .with_context(|| format!("cannot open store {}", path.display()))
    }

    /// How `--mmap` says to read stores.
    pub fn access(&self) -> oslf_format::StoreAccess {
        if self.mmap {
            oslf_format::StoreAccess::Mapped
        } else {
            oslf_format::StoreAccess::Positioned
        }
    }
}

/// The camera flags: each replaces one part of the store's camera.
#[derive(Args, Clone, Debug)]
pub struct CameraArgs {
    /// Camera position x,y,z [default: the store's camera, else one framing the object].
    #[arg(long, value_parser = parse_vec3)]
    pub camera_pos: Option<Vec3>,
    /// Camera target x,y,z.
    #[arg(long, value_parser = parse_vec3)]
    pub camera_target: Option<Vec3>,
    /// Vertical field of view in degrees.
    #[arg(long)]
    pub vfov: Option<f32>,
}

impl CameraArgs {
    /// `camera` with the given parts replaced, validated.
    pub fn apply(&self, mut camera: Camera) -> Result<Camera> {
        if let Some(p) = self.camera_pos {
            camera.position = p;
        }
        if let Some(p) = self.camera_target {
            camera.target = p;
        }
        if let Some(v) = self.vfov {
            camera.vfov_deg = v;
        }
        camera
            .validate()
            .map_err(|e| RuntimeError::Parameter(e.to_string()))?;
        Ok(camera)
    }
}

/// The background flag of the commands that show an image.
#[derive(Args, Clone, Debug)]
pub struct BackgroundArgs {
    /// What pixels off the object show (their alpha stays 0): none (black), env (the store's
    /// environment cube along each pixel's ray) or a linear colour R,G,B, each in [0, 1e6]
    /// [default: env; none, with a note, for a store without an environment cube].
    #[arg(long, value_name = "VALUE", value_parser = parse_background)]
    pub background: Option<Background>,
}

impl BackgroundArgs {
    /// The background for `store` (at `path`), and a note when it is not what the default
    /// promises. Without the flag: the environment cube, or none with the note "... has no
    /// environment cube ..." when the store has none. Errors when `--background env` is asked
    /// for and the store has none.
    pub fn resolve(&self, store: &Store, path: &Path) -> Result<(Background, Option<String>)> {
        let has_env = store.env_cube_index().is_some();
        match self.background {
            Some(Background::Env) if !has_env => Err(RuntimeError::Parameter(format!(
                "--background env: {} has no environment cube (bake with env_cube = true)",
                path.display()
            ))),
            Some(b) => Ok((b, None)),
            None if has_env => Ok((Background::Env, None)),
            None => Ok((
                Background::None,
                Some(format!(
                    "{} has no environment cube; background is black (bake with env_cube = true)",
                    path.display()
                )),
            )),
        }
    }
}

/// The largest component of a `--background` colour.
pub const MAX_BACKGROUND: f32 = 1e6;

/// `none`, `env`, or a linear colour `R,G,B` of three finite, non-negative numbers, each at
/// most [`MAX_BACKGROUND`].
pub fn parse_background(s: &str) -> std::result::Result<Background, String> {
    match s.trim() {
        "none" => Ok(Background::None),
        "env" => Ok(Background::Env),
        _ => {
            let bad = |why: String| {
                format!(
                    "{s:?} is not a background: none, env, or a linear colour R,G,B of three \
                     finite, non-negative numbers ({why})"
                )
            };
            let c = parse_vec3(s).map_err(bad)?;
            if c.min_element() < 0.0 {
                return Err(bad("a component is negative".into()));
            }
            // As for --exposure: past this every tone-mapped pixel of it is white.
            if c.max_element() > MAX_BACKGROUND {
                return Err(bad(format!("a component is above {MAX_BACKGROUND:e}")));
            }
            Ok(Background::Color(c.to_array()))
        }
    }
}

/// `per-point`, `per-direction`, `per-point-visible` or `per-point-searched`.
pub fn parse_order(s: &str) -> std::result::Result<Order, String> {
    s.parse::<Order>().map_err(|e| e.to_string())
}

/// `irradiance` or `samples`.
pub fn parse_diffuse(s: &str) -> std::result::Result<DiffuseSource, String> {
    DiffuseSource::ALL
        .into_iter()
        .find(|d| d.name() == s)
        .ok_or_else(|| format!("unknown diffuse source {s:?} (irradiance or samples)"))
}

/// `oslf`, `env` or `parallax`.
pub fn parse_source(s: &str) -> std::result::Result<Source, String> {
    s.parse::<Source>().map_err(|e| e.to_string())
}

/// `mip` or `point`.
pub fn parse_glossy_filter(s: &str) -> std::result::Result<GlossyFilter, String> {
    s.parse::<GlossyFilter>().map_err(|e| e.to_string())
}

/// Comma-separated numbers.
fn parse_numbers(s: &str) -> std::result::Result<Vec<f32>, String> {
    s.split(',')
        .map(|p| p.trim().parse::<f32>().map_err(|e| format!("{p:?}: {e}")))
        .collect()
}

/// Six finite numbers `xmin,ymin,zmin,xmax,ymax,zmax` with min < max on each axis.
pub fn parse_box(s: &str) -> std::result::Result<[[f32; 3]; 2], String> {
    let v = parse_numbers(s)?;
    match v.as_slice() {
        [a, b, c, d, e, f] if v.iter().all(|c| c.is_finite()) && a < d && b < e && c < f => {
            Ok([[*a, *b, *c], [*d, *e, *f]])
        }
        _ => Err(format!(
            "{s:?} is not a box xmin,ymin,zmin,xmax,ymax,zmax (six finite numbers, min < max)"
        )),
    }
}

/// The range of an exposure multiplier: beyond it every pixel of a PNG is black or white.
pub const EXPOSURE_RANGE: std::ops::RangeInclusive<f32> = 1e-6..=1e6;

/// An exposure multiplier: finite, positive and within [`EXPOSURE_RANGE`] (outside it, any
/// radiance a scene holds maps to an all-black or all-white image).
pub fn parse_exposure(s: &str) -> std::result::Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(v) if EXPOSURE_RANGE.contains(&v) => Ok(v),
        _ => Err(format!(
            "{s:?} is not an exposure between {:e} and {:e} (it multiplies every pixel; 1 leaves them as they are; beyond that range every pixel is black or white)",
            EXPOSURE_RANGE.start(),
            EXPOSURE_RANGE.end()
        )),
    }
}

/// Three finite numbers `x,y,z`.
pub fn parse_vec3(s: &str) -> std::result::Result<Vec3, String> {
    let v = parse_numbers(s)?;
    match v.as_slice() {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok(Vec3::new(*x, *y, *z)),
        _ => Err(format!("{s:?} is not three finite numbers x,y,z")),
    }
}

/// The most worker threads `-j` starts per core this process may use.
pub const THREADS_PER_CORE: usize = 4;

/// Runs `f` in a worker pool of `threads` threads (`-j`; all cores when `None`). The results
/// of the commands that take `-j` do not depend on it.
pub fn in_pool<T: Send>(
    threads: Option<usize>,
    f: impl FnOnce() -> anyhow::Result<T> + Send,
) -> anyhow::Result<T> {
    let mut pool = rayon::ThreadPoolBuilder::new();
    if let Some(n) = threads {
        if n == 0 {
            anyhow::bail!("--threads must be at least 1");
        }
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        let max = THREADS_PER_CORE * cores;
        if n > max {
            anyhow::bail!(
                "--threads {n} is more than {max} ({THREADS_PER_CORE} × the {cores} cores this process may use); more threads only add overhead, and the output is the same for any count"
            );
        }
        pool = pool.num_threads(n);
    }
    let pool = pool.build().context("cannot start worker threads")?;
    pool.install(f)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn backgrounds_parse_and_bad_ones_say_why() {
        assert_eq!(parse_background("none"), Ok(Background::None));
        assert_eq!(parse_background("env"), Ok(Background::Env));
        assert_eq!(
            parse_background("0.5, 1,2e1"),
            Ok(Background::Color([0.5, 1.0, 20.0]))
        );
        for (bad, says) in [
            ("1,2", "three finite"),
            ("1,-2,3", "negative"),
            ("1,inf,3", "three finite"),
            ("1,NaN,3", "three finite"),
            ("1,1e30,3", "above 1e6"),
            ("sky", "\"sky\""),
        ] {
            let e = parse_background(bad).unwrap_err();
            assert!(
                e.contains("none, env, or a linear colour") && e.contains(says),
                "{bad}: {e}"
            );
        }
    }

    #[derive(clap::Parser)]
    struct Shading {
        #[command(flatten)]
        shading: ShadingArgs,
    }

    /// The blend's power: 2 with depth-corrected lookups, the thesis's 4 with plain ones, and
    /// `-N` over either; it reaches the parameters a frame is shaded with.
    #[test]
    fn the_blend_power_follows_the_lookups_unless_given() {
        use clap::Parser;
        for (flags, want) in [
            (&[][..], 2.0),
            (&["--no-depth"][..], 4.0),
            (&["--no-depth", "-N", "3"][..], 3.0),
            (&["-N", "0"][..], 0.0),
        ] {
            let args =
                Shading::try_parse_from(std::iter::once("oslf").chain(flags.iter().copied()))
                    .unwrap()
                    .shading;
            assert_eq!(args.blend_n(), want, "{flags:?}");
            let p = args.params(Mode::Mirror, Blend::Normal).unwrap();
            assert_eq!(p.blend(), Some((Blend::Normal, want)), "{flags:?}");
        }
    }

    /// The orders that read the distance channel are refused with plain lookups, naming the
    /// order and the flag; with depth-corrected lookups they are accepted.
    #[test]
    fn orders_that_read_distances_need_depth_corrected_lookups() {
        use clap::Parser;
        let parse = |flags: &[&str]| {
            Shading::try_parse_from(std::iter::once("oslf").chain(flags.iter().copied()))
                .unwrap()
                .shading
        };
        for order in ["per-point-visible", "per-point-searched"] {
            let e = parse(&["--order", order, "--no-depth"])
                .params(Mode::Glossy, Blend::Normal)
                .unwrap_err()
                .to_string();
            assert!(e.contains(order) && e.contains("--no-depth"), "{e}");
            assert!(parse(&["--order", order])
                .params(Mode::Glossy, Blend::Normal)
                .is_ok());
        }
        for order in ["per-point", "per-direction"] {
            assert!(parse(&["--order", order, "--no-depth"])
                .params(Mode::Glossy, Blend::Normal)
                .is_ok());
        }
    }
}
