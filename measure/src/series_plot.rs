//! Error against cost for several series of one setting (samples per texel, say), each series
//! one way of paying (a device, a scene): a line per series through its points, each point
//! labelled with its value, the cost on a logarithmic axis. PNG and SVG, as [`crate::plot`].

use std::path::Path;

use plotters::element::DashedPathElement;
use plotters::prelude::*;

use crate::error::{MeasureError, Result};
use crate::plot::{write_png_and_svg, Figure, PlotText, FONT};

/// One series: its name in the legend and its points (cost, error, label).
#[derive(Clone, Debug)]
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64, String)>,
    /// Dashed: a second measure of the same series (recon + mirror beside mirror, say).
    pub dashed: bool,
    /// Index into the palette: series of one device, say, share their colour.
    pub colour: usize,
}

/// The palette [`Series::colour`] indexes (modulo its length).
const COLOURS: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
    RGBColor(23, 190, 207),
];

/// Writes the series as one chart to `png` and `svg`, `size` pixels; points with a cost that
/// is not positive and finite, or an error that is not finite, are refused.
pub fn plot_series(
    series: &[Series],
    text: &PlotText,
    png: &Path,
    svg: &Path,
    size: (u32, u32),
) -> Result<()> {
    if series.iter().all(|s| s.points.is_empty()) {
        return Err(MeasureError::Invalid(
            "nothing to plot: no series has a point".into(),
        ));
    }
    for s in series {
        if let Some((c, e, l)) = s
            .points
            .iter()
            .find(|(c, e, _)| !(c.is_finite() && *c > 0.0 && e.is_finite()))
        {
            return Err(MeasureError::Invalid(format!(
                "series {:?}, point {l:?}: cost {c} and error {e} cannot be plotted (cost > 0, both finite)",
                s.name
            )));
        }
    }
    write_png_and_svg(&Chart { series, text }, png, svg, size)
}

struct Chart<'a> {
    series: &'a [Series],
    text: &'a PlotText,
}

impl Figure for Chart<'_> {
    fn draw<DB: DrawingBackend>(
        &self,
        root: DrawingArea<DB, plotters::coord::Shift>,
    ) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
        root.fill(&WHITE)?;
        let points = || self.series.iter().flat_map(|s| &s.points);
        let x0 = points().map(|p| p.0).fold(f64::MAX, f64::min);
        let x1 = points().map(|p| p.0).fold(f64::MIN, f64::max);
        let y1 = points().map(|p| p.1).fold(f64::MIN, f64::max);
        let mut chart = ChartBuilder::on(&root)
            .caption(&self.text.caption, (FONT, 20))
            .margin(14)
            .x_label_area_size(44)
            .y_label_area_size(64)
            .build_cartesian_2d((x0 / 1.3..x1 * 1.6).log_scale().base(2.0), 0.0..y1 * 1.08)?;
        chart
            .configure_mesh()
            .light_line_style(WHITE)
            .x_labels(16)
            .x_label_formatter(&|x| format!("{x}"))
            .x_desc(&self.text.x)
            .y_desc(&self.text.y)
            .label_style((FONT, 13))
            .axis_desc_style((FONT, 15))
            .draw()?;
        for s in self.series {
            let colour = COLOURS[s.colour % COLOURS.len()];
            let style = colour.stroke_width(2);
            let line: Vec<(f64, f64)> = s.points.iter().map(|p| (p.0, p.1)).collect();
            if s.dashed {
                chart
                    .draw_series(DashedLineSeries::new(line, 8, 5, style))?
                    .label(&s.name)
                    .legend(move |(x, y)| {
                        DashedPathElement::new(vec![(x, y), (x + 20, y)], 5, 3, style)
                    });
            } else {
                chart
                    .draw_series(LineSeries::new(line, style))?
                    .label(&s.name)
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], style));
            }
            chart.draw_series(
                s.points
                    .iter()
                    .map(|p| Circle::new((p.0, p.1), 4, colour.filled())),
            )?;
            chart.draw_series(s.points.iter().map(|p| {
                Text::new(
                    p.2.clone(),
                    (p.0 * 1.04, p.1 + 0.012 * y1),
                    (FONT, 12).into_font().color(&BLACK),
                )
            }))?;
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerLeft)
            .label_font((FONT, 13))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()?;
        root.present()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_each_series_and_refuses_what_it_cannot_place() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path();
        let (png, svg) = (dir.join("s.png"), dir.join("s.svg"));
        let text = PlotText {
            caption: "error against bake time".into(),
            x: "bake, s".into(),
            y: "RMSE L*".into(),
        };
        let series = |name: &str, scale: f64, dashed, colour| Series {
            name: name.into(),
            points: [(4, 9.0), (16, 7.0), (64, 6.0)]
                .iter()
                .map(|&(n, e)| (scale * n as f64, e, n.to_string()))
                .collect(),
            dashed,
            colour,
        };
        let all = [series("gpu", 0.1, false, 0), series("cpu", 2.0, true, 1)];
        plot_series(&all, &text, &png, &svg, (640, 400)).unwrap();
        let img = image::open(&png).unwrap().to_rgb8();
        assert_eq!(img.dimensions(), (640, 400));
        // Both series' colours were drawn.
        for c in &COLOURS[..2] {
            assert!(img.pixels().any(|p| p.0 == [c.0, c.1, c.2]), "{c:?}");
        }
        let s = std::fs::read_to_string(&svg).unwrap();
        assert!(s.contains("gpu") && s.contains("cpu") && s.contains("\n64\n"));
        let mut bad = all.clone();
        bad[1].points[2].0 = 0.0;
        let e = plot_series(&bad, &text, &png, &svg, (64, 64)).unwrap_err();
        assert!(e.to_string().contains("\"cpu\", point \"64\""), "{e}");
        assert!(plot_series(&[], &text, &png, &svg, (64, 64)).is_err());
    }
}
