//! The speed/accuracy plot: one panel per kind of time (e.g. frame time, bake time), error
//! against it, every configuration a point, the panel's Pareto front drawn through its points and
//! labelled, the defaults marked. PNG and SVG, drawn with plotters; text is set in the embedded
//! DejaVu Sans, so no system fonts are needed.

use std::path::Path;
use std::sync::Once;

use plotters::prelude::*;

use crate::error::{MeasureError, Result};

/// One configuration in the plot.
#[derive(Clone, Debug)]
pub struct PlotPoint {
    pub label: String,
    /// The time (x): a frame's milliseconds, a bake's seconds, …
    pub time_ms: f64,
    /// Error (y).
    pub error: f64,
    pub on_front: bool,
    pub is_default: bool,
}

/// Axis titles and caption.
#[derive(Clone, Debug)]
pub struct PlotText {
    pub caption: String,
    pub x: String,
    pub y: String,
}

/// One panel: its points and titles.
#[derive(Clone, Debug)]
pub struct Panel {
    pub points: Vec<PlotPoint>,
    pub text: PlotText,
}

pub(crate) const FONT: &str = "sans-serif";

fn register_font() -> Result<()> {
    static ONCE: Once = Once::new();
    let mut result = Ok(());
    ONCE.call_once(|| {
        result = plotters::style::register_font(FONT, FontStyle::Normal, dejavu::sans::regular())
            .map_err(|_| MeasureError::Invalid("the embedded DejaVu Sans font is invalid".into()));
    });
    result
}

fn draw_err<E: std::error::Error>(path: &Path) -> impl Fn(E) -> MeasureError + '_ {
    move |e| MeasureError::Output {
        path: path.to_path_buf(),
        message: format!("cannot draw the plot: {e}"),
    }
}

/// Writes the panels side by side as PNG (`png`) and SVG (`svg`), `size` pixels in all.
pub fn plot_tradeoff(panels: &[Panel], png: &Path, svg: &Path, size: (u32, u32)) -> Result<()> {
    let panels: Vec<(Vec<&PlotPoint>, &PlotText)> = panels
        .iter()
        .map(|p| {
            let finite = p
                .points
                .iter()
                .filter(|q| q.time_ms.is_finite() && q.time_ms > 0.0 && q.error.is_finite())
                .collect();
            (finite, &p.text)
        })
        .collect();
    if panels.is_empty() || panels.iter().any(|(p, _)| p.is_empty()) {
        return Err(MeasureError::Invalid(
            "nothing to plot: a panel has no finite point".into(),
        ));
    }
    write_png_and_svg(&Panels(panels), png, svg, size)
}

/// A figure drawn the same way on the SVG and the bitmap backend.
pub(crate) trait Figure {
    fn draw<DB: DrawingBackend>(
        &self,
        root: DrawingArea<DB, plotters::coord::Shift>,
    ) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>>;
}

/// Draws `figure` as SVG (`svg`) and PNG (`png`), `size` pixels, in the embedded font.
pub(crate) fn write_png_and_svg(
    figure: &impl Figure,
    png: &Path,
    svg: &Path,
    size: (u32, u32),
) -> Result<()> {
    register_font()?;
    let mut text = String::new();
    figure
        .draw(SVGBackend::with_string(&mut text, size).into_drawing_area())
        .map_err(draw_err(svg))?;
    let mut buffer = vec![0u8; size.0 as usize * size.1 as usize * 3];
    figure
        .draw(BitMapBackend::with_buffer(&mut buffer, size).into_drawing_area())
        .map_err(draw_err(png))?;
    // Both through the one way out (oslf_util::output_file): checked, synced, renamed.
    oslf_util::output_file::write_bytes(svg, text.as_bytes())?;
    oslf_util::output_file::write_with(png, |w| {
        image::write_buffer_with_format(
            w,
            &buffer,
            size.0,
            size.1,
            image::ColorType::Rgb8,
            image::ImageFormat::Png,
        )
        .map_err(std::io::Error::other)
    })?;
    Ok(())
}

/// The trade-off's panels side by side.
struct Panels<'a>(Vec<(Vec<&'a PlotPoint>, &'a PlotText)>);

impl Figure for Panels<'_> {
    fn draw<DB: DrawingBackend>(
        &self,
        root: DrawingArea<DB, plotters::coord::Shift>,
    ) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
        root.fill(&WHITE)?;
        let areas = root.split_evenly((1, self.0.len()));
        for (area, (points, text)) in areas.into_iter().zip(&self.0) {
            draw(area, points, text)?;
        }
        root.present()
    }
}

fn draw<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    points: &[&PlotPoint],
    text: &PlotText,
) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let (mut x0, mut x1) = (f64::MAX, f64::MIN);
    let (mut y0, mut y1) = (f64::MAX, f64::MIN);
    for p in points {
        x0 = x0.min(p.time_ms);
        x1 = x1.max(p.time_ms);
        y0 = y0.min(p.error);
        y1 = y1.max(p.error);
    }
    let xpad = (x1 - x0) * 0.08 + 1e-3 * x1;
    let (x0, x1) = ((x0 - xpad).max(0.0), x1 + 3.0 * xpad);
    let pad = ((y1 - y0) * 0.08).max(1e-6 * y1.abs().max(1e-12));
    let (y0, y1) = ((y0 - pad).max(0.0), y1 + pad);
    let mut chart = ChartBuilder::on(&root)
        .caption(&text.caption, (FONT, 20))
        .margin(14)
        .x_label_area_size(44)
        .y_label_area_size(64)
        .build_cartesian_2d(x0..x1, y0..y1)?;
    chart
        .configure_mesh()
        .light_line_style(WHITE)
        .x_desc(&text.x)
        .y_desc(&text.y)
        .label_style((FONT, 13))
        .axis_desc_style((FONT, 15))
        .draw()?;
    let grey = RGBColor(120, 120, 120);
    chart
        .draw_series(
            points
                .iter()
                .filter(|p| !p.on_front)
                .map(|p| Circle::new((p.time_ms, p.error), 4, grey.filled())),
        )?
        .label("configuration")
        .legend(move |(x, y)| Circle::new((x + 10, y), 4, grey.filled()));
    let mut front: Vec<&&PlotPoint> = points.iter().filter(|p| p.on_front).collect();
    front.sort_by(|a, b| a.time_ms.total_cmp(&b.time_ms));
    chart
        .draw_series(LineSeries::new(
            front.iter().map(|p| (p.time_ms, p.error)),
            RED.stroke_width(2),
        ))?
        .label("Pareto front")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RED.stroke_width(2)));
    chart.draw_series(
        front
            .iter()
            .map(|p| Circle::new((p.time_ms, p.error), 5, RED.filled())),
    )?;
    chart.draw_series(front.iter().map(|p| {
        Text::new(
            p.label.clone(),
            (p.time_ms + 0.01 * (x1 - x0), p.error),
            (FONT, 12).into_font().color(&BLACK),
        )
    }))?;
    chart
        .draw_series(
            points
                .iter()
                .filter(|p| p.is_default)
                .map(|p| Cross::new((p.time_ms, p.error), 9, BLUE.stroke_width(2))),
        )?
        .label("defaults")
        .legend(|(x, y)| Cross::new((x + 10, y), 6, BLUE.stroke_width(2)));
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .label_font((FONT, 13))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_a_png_and_an_svg() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path();
        let pts: Vec<PlotPoint> = [(20.0, 0.2, true), (40.0, 0.1, true), (45.0, 0.15, false)]
            .iter()
            .enumerate()
            .map(|(i, &(t, e, f))| PlotPoint {
                label: format!("c{i}"),
                time_ms: t,
                error: e,
                on_front: f,
                is_default: i == 1,
            })
            .collect();
        let text = PlotText {
            caption: "error vs time".into(),
            x: "frame time (ms)".into(),
            y: "RMSE L*".into(),
        };
        let (png, svg) = (dir.join("p.png"), dir.join("p.svg"));
        let panel = Panel { points: pts, text };
        plot_tradeoff(&[panel.clone(), panel.clone()], &png, &svg, (640, 400)).unwrap();
        let img = image::open(&png).unwrap().to_rgb8();
        assert_eq!(img.dimensions(), (640, 400));
        // Something red (the front) and something not white was drawn.
        assert!(img
            .pixels()
            .any(|p| p.0[0] > 200 && p.0[1] < 60 && p.0[2] < 60));
        let s = std::fs::read_to_string(&svg).unwrap();
        assert!(s.contains("<svg") && s.contains("Pareto front") && s.contains("c0"));
        assert!(plot_tradeoff(&[], &png, &svg, (64, 64)).is_err());
        let empty = Panel {
            points: vec![],
            text: panel.text,
        };
        assert!(plot_tradeoff(&[empty], &png, &svg, (64, 64)).is_err());
    }
}
