//! Judging a runtime configuration: render it, compare it with the ground truth (thesis §6.1),
//! and time it, in one run.

use std::time::Instant;

use crate::metrics::{compare, Metrics};
use oslf_geometry::camera::Camera;
use oslf_runtime::{Frame, Mode, RenderOptions, Renderer, ShadingParams};
use oslf_trace::ashikhmin_shirley::AsLobe;
use oslf_trace::ground_truth::{compose, GroundTruth, Term, TruthImage, TruthSettings};
use serde::Serialize;

use crate::error::{MeasureError, Result};

/// The reference white of the CIELAB conversion (linear 1.0 = L* 100; see
/// [`crate::metrics`]).
pub const WHITE: f64 = 1.0;

/// What one configuration measured.
#[derive(Clone, Debug, Serialize)]
pub struct Judgement {
    pub metrics: Metrics,
    /// The first frame: pipeline compilation (if the mode is new to this renderer), cube
    /// decoding and upload of what it misses, shading, read-back.
    pub cold_ms: f64,
    /// Median of the warm frames (every needed cube resident, image not read back), timed to
    /// GPU completion.
    pub frame_ms: f64,
    pub warm_frames: u32,
}

/// Renders `params` from `camera` at the truth's size, compares the image with `truth` over
/// the pixels that are on the object in both, and times `warm_frames` further frames.
pub fn judge(
    renderer: &mut Renderer,
    camera: &Camera,
    params: &ShadingParams,
    truth: &TruthImage,
    warm_frames: u32,
) -> Result<(Judgement, Frame)> {
    let mut opts = RenderOptions {
        width: truth.width,
        height: truth.height,
        ..RenderOptions::default()
    };
    let t = Instant::now();
    let frame = renderer.render(camera, params, &opts)?;
    let cold_ms = t.elapsed().as_secs_f64() * 1e3;
    let metrics = compare_frame(truth, &frame)?;
    opts.read_pixels = false;
    let mut times = Vec::with_capacity(warm_frames as usize);
    for _ in 0..warm_frames {
        let t = Instant::now();
        renderer.render(camera, params, &opts)?;
        times.push(t.elapsed().as_secs_f64() * 1e3);
    }
    Ok((
        Judgement {
            metrics,
            cold_ms,
            frame_ms: median(&mut times).unwrap_or(cold_ms),
            warm_frames,
        },
        frame,
    ))
}

/// One configuration to time: an index into the renderers, the view and the settings.
#[derive(Clone, Copy, Debug)]
pub struct TimedJob {
    pub renderer: usize,
    pub camera: Camera,
    pub params: ShadingParams,
}

/// Times every job `rounds` times, interleaved (each job once, then each again, …), after one
/// untimed frame each, so that the load of a shared machine falls on every job alike; returns
/// each job's median frame time in ms (timed to GPU completion, image not read back).
pub fn time_interleaved(
    renderers: &mut [Renderer],
    jobs: &[TimedJob],
    width: u32,
    height: u32,
    rounds: u32,
) -> Result<Vec<f64>> {
    let opts = RenderOptions {
        width,
        height,
        read_pixels: false,
        ..RenderOptions::default()
    };
    let mut frame = |job: &TimedJob| -> Result<f64> {
        let r = renderers.get_mut(job.renderer).ok_or_else(|| {
            MeasureError::Invalid(format!("no renderer {} to time", job.renderer))
        })?;
        let t = Instant::now();
        r.render(&job.camera, &job.params, &opts)?;
        Ok(t.elapsed().as_secs_f64() * 1e3)
    };
    for job in jobs {
        frame(job)?;
    }
    let mut times = vec![Vec::with_capacity(rounds as usize); jobs.len()];
    for _ in 0..rounds {
        for (job, t) in jobs.iter().zip(&mut times) {
            t.push(frame(job)?);
        }
    }
    Ok(times
        .iter_mut()
        .map(|t| median(t).unwrap_or(f64::NAN))
        .collect())
}

/// The error of a rendered frame against the truth, over pixels on the object in both.
pub fn compare_frame(truth: &TruthImage, frame: &Frame) -> Result<Metrics> {
    if (frame.width, frame.height) != (truth.width, truth.height) {
        return Err(MeasureError::Invalid(format!(
            "frame {}x{} and ground truth {}x{} differ in size",
            frame.width, frame.height, truth.width, truth.height
        )));
    }
    let (t, f) = (&truth.pixels, &frame.pixels);
    compare(
        t,
        f,
        truth.width as usize,
        |i| t[i][3] > 0.5 && f[i][3] > 0.5,
        WHITE,
    )
}

/// The median, `None` for no values.
pub fn median(v: &mut [f64]) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let m = v.len() / 2;
    Some(if v.len() % 2 == 1 {
        v[m]
    } else {
        0.5 * (v[m - 1] + v[m])
    })
}

/// The ground truth of a runtime mode: its terms rendered by [`GroundTruth`] and composed as
/// the runtime composes them (Eq. 4.12). The glossy truth is the specular term alone, so
/// `params.rd` must be 0.
pub fn render_truth(
    truth: &GroundTruth,
    params: &ShadingParams,
    settings: &TruthSettings,
) -> Result<TruthImage> {
    let as_lobe = params.lobe().unwrap_or_default();
    if as_lobe.rd > 0.0 {
        return Err(MeasureError::Invalid(
            "the ground truth has the Ashikhmin–Shirley specular term only: use R_d = 0".into(),
        ));
    }
    let lobe = Term::Glossy(AsLobe {
        rs: as_lobe.rs.into(),
        nu: as_lobe.nu.into(),
        nv: as_lobe.nv.into(),
    });
    let material = params.material().unwrap_or_default();
    Ok(match params.mode() {
        Mode::Recon => truth.render(Term::Recon, settings)?,
        Mode::Mirror => truth.render(Term::Mirror, settings)?,
        Mode::Glossy => truth.render(lobe, settings)?,
        Mode::ReconMirror => compose(
            &truth.render(Term::Recon, settings)?,
            &truth.render(Term::Mirror, settings)?,
        )?,
        Mode::ReconGlossy => compose(
            &truth.render(Term::Recon, settings)?,
            &truth.render(lobe, settings)?,
        )?,
        Mode::Pbr => truth.render(
            Term::Pbr {
                metallic: material.metallic,
                roughness: material.roughness,
                object_material: material.object_material,
            },
            settings,
        )?,
    })
}
