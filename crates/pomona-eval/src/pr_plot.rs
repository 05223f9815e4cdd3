//! The precision-recall curve as a PNG.
//!
//! Drawn with `plotters`' bitmap backend into memory and written through `pomona-io`'s atomic PNG
//! writer. Text uses DejaVu Sans compiled into the binary (from the `dejavu` crate) and rendered
//! by `ab_glyph`, so no system font or font library is needed at build or run time.

use std::path::Path;
use std::sync::OnceLock;

use plotters::prelude::*;
use plotters::style::{register_font, FontStyle};
use pomona_core::ColorImage;

use crate::{EvalError, PrCurve};

const WIDTH: u32 = 800;
const HEIGHT: u32 = 600;

/// Registers the embedded font once per process; `false` if it could not be parsed.
fn font_ready() -> bool {
    static READY: OnceLock<bool> = OnceLock::new();
    *READY.get_or_init(|| {
        register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular()).is_ok()
    })
}

/// Renders `curve` (the step curve, the 11 VOC interpolation points and the operating point at
/// `threshold`) with `title` into an RGB buffer of `WIDTH × HEIGHT`.
fn render(curve: &PrCurve, title: &str, threshold: f64) -> Result<Vec<u8>, String> {
    let mut buf = vec![255u8; (WIDTH * HEIGHT * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (WIDTH, HEIGHT)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 22))
            .margin(16)
            .x_label_area_size(44)
            .y_label_area_size(54)
            .build_cartesian_2d(0.0f64..1.0, 0.0f64..1.02)
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .x_desc("recall")
            .y_desc("precision")
            .x_labels(11)
            .y_labels(11)
            .label_style(("sans-serif", 14))
            .draw()
            .map_err(|e| e.to_string())?;
        // Step curve: from (0, p₁) through each point, precision held until the next recall.
        let mut steps = Vec::with_capacity(2 * curve.points.len() + 1);
        let mut last_recall = 0.0;
        for p in &curve.points {
            steps.push((last_recall, p.precision));
            steps.push((p.recall, p.precision));
            last_recall = p.recall;
        }
        let blue = RGBColor(31, 97, 180);
        chart
            .draw_series(LineSeries::new(steps, blue.stroke_width(2)))
            .map_err(|e| e.to_string())?
            .label(format!("all-point AP {:.3}", curve.ap_all_points()))
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], blue.stroke_width(2))
            });
        let voc: Vec<(f64, f64)> = (0..=10)
            .map(|i| {
                let r = f64::from(i) / 10.0;
                let p = curve
                    .points
                    .iter()
                    .filter(|p| p.recall >= r)
                    .map(|p| p.precision)
                    .fold(0.0, f64::max);
                (r, p)
            })
            .collect();
        let orange = RGBColor(230, 120, 20);
        chart
            .draw_series(
                voc.into_iter()
                    .map(|(r, p)| Circle::new((r, p), 4, orange.filled())),
            )
            .map_err(|e| e.to_string())?
            .label(format!("VOC 11-point AP {:.3}", curve.ap_voc11()))
            .legend(move |(x, y)| Circle::new((x + 10, y), 4, orange.filled()));
        if let Some(op) = curve.at_threshold(threshold) {
            chart
                .draw_series(std::iter::once(TriangleMarker::new(
                    (op.recall, op.precision),
                    8,
                    BLACK.filled(),
                )))
                .map_err(|e| e.to_string())?
                .label(format!("score ≥ {threshold}"))
                .legend(|(x, y)| TriangleMarker::new((x + 10, y), 6, BLACK.filled()));
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerLeft)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 15))
            .draw()
            .map_err(|e| e.to_string())?;
        root.present().map_err(|e| e.to_string())?;
    }
    Ok(buf)
}

/// Writes the precision-recall curve as an 800×600 PNG (atomically).
///
/// # Errors
/// [`EvalError::Plot`] when drawing fails, and the PNG writer's errors naming `path`.
pub fn write_pr_plot(
    path: &Path,
    curve: &PrCurve,
    title: &str,
    threshold: f64,
) -> Result<(), EvalError> {
    let plot_err = |message: String| EvalError::Plot {
        path: path.to_owned(),
        message,
    };
    if !font_ready() {
        return Err(plot_err("the embedded font could not be loaded".into()));
    }
    let rgb = render(curve, title, threshold).map_err(plot_err)?;
    let image = ColorImage::from_rgb(WIDTH, HEIGHT, rgb).map_err(|e| plot_err(e.to_string()))?;
    pomona_io::write_color_png(path, &image)?;
    Ok(())
}
