//! Overlay images: truth and detections drawn on a frame's colour image, for looking at what a
//! detector did (`pomona demo`, `pomona detect --overlay`).
//!
//! Truth fruit: green — a cross at the projected centre and the fruit's image circle (its
//! `center_px`/`radius_px`, or its sphere projected: `pomona_core::ImageCircle`); truth that
//! evaluation ignores (visibility below the threshold) is drawn thinner in a pale green; truth
//! without a 3D centre also gets its box. Detections: red — their image circle by the same rule
//! (color-contour's own circle, a sphere projected, a box's inscribed circle, or a small fixed
//! circle when the method gives no size), a dot at the centre and a label `score | ⌀ mm`. Frames without colour are drawn on their depth as grey.
//! Tracks (`pomona track --overlay`): the tracker's circle red, the target's truth circle green.
//! Stereo frames (`pomona stereo --overlay`): the two shots side by side, each view's circles,
//! and a line per located pair.
//! Drawing uses `plotters`' bitmap backend on the image buffer and DejaVu Sans compiled into the
//! binary (via `ab_glyph`), as `pomona-eval`'s PR plots do, so no system font is needed.

use std::path::Path;
use std::sync::OnceLock;

use anyhow::{anyhow, bail, Result};
use plotters::prelude::*;
use plotters::style::{register_font, FontStyle};
use pomona_core::{
    ColorImage, DepthImage, Detection, FrameTruth, FruitTruth, ImageCircle, PinholeCamera,
};
use pomona_io::Dataset;

/// Radius, pixels, of a detection without a diameter.
const NO_SIZE_RADIUS_PX: i32 = 6;
const TRUTH: RGBColor = RGBColor(40, 230, 60);
const TRUTH_IGNORED: RGBColor = RGBColor(160, 230, 170);
const DETECTION: RGBColor = RGBColor(240, 30, 30);

/// Registers the embedded font once per process; `false` if it could not be parsed.
fn font_ready() -> bool {
    static READY: OnceLock<bool> = OnceLock::new();
    *READY.get_or_init(|| {
        register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular()).is_ok()
    })
}

/// What an overlay of `frame` is drawn on (its colour image, or its depth as grey) and its truth.
///
/// # Errors
/// The dataset's errors reading the frame or its truth, naming the file.
pub fn view_of(dataset: &Dataset, frame: &str) -> Result<(ColorImage, Option<FrameTruth>)> {
    let rgbd = dataset.load_frame(frame)?;
    let image = match rgbd.color() {
        Some(c) => c.clone(),
        None => depth_as_gray(rgbd.depth()),
    };
    Ok((image, dataset.load_truth(frame)?))
}

/// The detections an overlay shows: those scoring at least `threshold` (below it a detector
/// has rejected them), in their order.
pub fn shown(detections: &[Detection], threshold: f64) -> Vec<Detection> {
    detections
        .iter()
        .filter(|d| d.score >= threshold)
        .cloned()
        .collect()
}

/// Depth as a grey image (near = bright, no reading = black), for frames without colour.
pub fn depth_as_gray(depth: &DepthImage) -> ColorImage {
    let (lo, hi) = depth.range_m().unwrap_or((0.0, 1.0));
    let span = (hi - lo).max(1e-6);
    let mut img = ColorImage::filled(depth.width(), depth.height(), [0, 0, 0]);
    for v in 0..depth.height() {
        for u in 0..depth.width() {
            if let Some(z) = depth.get(u, v).filter(|z| z.is_finite()) {
                let g = (235.0 - 200.0 * (z - lo) / span).clamp(0.0, 255.0) as u8;
                img.set(u, v, [g, g, g]);
            }
        }
    }
    img
}

fn to_px(x: f64) -> i32 {
    x.round().clamp(-1e6, 1e6) as i32
}

fn draw_err<E: std::fmt::Debug>(e: E) -> anyhow::Error {
    anyhow!("drawing the overlay: {e:?}")
}

/// Draws `truth` (green) and `detections` (red) onto a copy of `image` and puts `title` in the top
/// left corner. Truth with visibility below `min_visibility` is drawn pale.
///
/// # Errors
/// If the embedded font cannot be loaded or drawing fails.
pub fn draw_overlay(
    image: &ColorImage,
    camera: &PinholeCamera,
    truth: Option<&FrameTruth>,
    detections: &[Detection],
    min_visibility: f64,
    title: &str,
) -> Result<ColorImage> {
    let size = (image.width(), image.height());
    draw_on(image, title, |root| {
        for fruit in truth.map(|t| t.fruits.as_slice()).unwrap_or_default() {
            draw_truth(root, camera, fruit, min_visibility, 0.0)?;
        }
        let det_style = ("sans-serif", 13).into_font().color(&DETECTION);
        for d in detections {
            draw_detection(root, camera, d, &det_style, size)?;
        }
        Ok(())
    })
}

/// A tracked circle (red, with a dot at its centre) and the target's truth circle when known
/// (green), on `image` with `title` in the top left corner, written as a PNG (`pomona track
/// --overlay`).
///
/// # Errors
/// Drawing errors and the PNG writer's errors naming `path`.
pub fn write_track_overlay(
    path: &Path,
    image: &ColorImage,
    estimate: &ImageCircle,
    truth: Option<&ImageCircle>,
    title: &str,
) -> Result<()> {
    let img = draw_on(image, title, |root| {
        for (circle, color) in truth
            .map(|t| (t, TRUTH))
            .into_iter()
            .chain([(estimate, DETECTION)])
        {
            let center = (to_px(circle.center_px.x), to_px(circle.center_px.y));
            draw_ring(root, center, to_px(circle.radius_px).max(2), color)?;
        }
        Ok(())
    })?;
    pomona_io::write_color_png(path, &img)?;
    Ok(())
}

type Area<'a> = DrawingArea<BitMapBackend<'a>, plotters::coord::Shift>;

/// A copy of `image` with `draw` applied and `title` in the top left corner.
fn draw_on(
    image: &ColorImage,
    title: &str,
    draw: impl FnOnce(&Area<'_>) -> Result<()>,
) -> Result<ColorImage> {
    if !font_ready() {
        bail!("drawing the overlay: the embedded font could not be loaded");
    }
    let (w, h) = (image.width(), image.height());
    let mut buf = image.as_rgb().to_vec();
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        draw(&root)?;
        draw_title(&root, title)?;
        root.present().map_err(draw_err)?;
    }
    ColorImage::from_rgb(w, h, buf).map_err(|e| anyhow!("drawing the overlay: {e}"))
}

/// A circle of radius `r` around `(x, y)` in `color`, two pixels wide, with a dot at its centre.
fn draw_ring(root: &Area<'_>, (x, y): (i32, i32), r: i32, color: RGBColor) -> Result<()> {
    root.draw(&Circle::new((x, y), r, color.stroke_width(2)))
        .map_err(draw_err)?;
    root.draw(&Circle::new((x, y), 2, color.filled()))
        .map_err(draw_err)?;
    Ok(())
}

/// `title` in white on a dark box in the top left corner (nothing when empty).
fn draw_title(root: &Area<'_>, title: &str) -> Result<()> {
    if title.is_empty() {
        return Ok(());
    }
    let style = ("sans-serif", 14).into_font().color(&WHITE);
    let (tw, th) = root.estimate_text_size(title, &style).map_err(draw_err)?;
    root.draw(&Rectangle::new(
        [(0, 0), (tw as i32 + 8, th as i32 + 6)],
        BLACK.mix(0.6).filled(),
    ))
    .map_err(draw_err)?;
    root.draw(&Text::new(title.to_owned(), (4, 3), style))
        .map_err(draw_err)?;
    Ok(())
}

/// One truth fruit: cross, circle, and box when it has no 3D centre (see the module docs),
/// `dx` pixels to the right of where `camera` sees it.
fn draw_truth(
    root: &Area<'_>,
    camera: &PinholeCamera,
    fruit: &FruitTruth,
    min_visibility: f64,
    dx: f64,
) -> Result<()> {
    let ignored = fruit.visibility.is_some_and(|v| v < min_visibility);
    let color = if ignored { TRUTH_IGNORED } else { TRUTH };
    let width = if ignored { 1 } else { 2 };
    // The circle only when the fruit states one (not the box's inscribed circle).
    let stated = (fruit.center_px.is_some() && fruit.radius_px.is_some())
        || (fruit.center_m.is_some() && fruit.diameter_m.is_some());
    let circle = fruit.image_circle(camera).filter(|_| stated);
    let center = fruit
        .center_m
        .and_then(|c| camera.project(&c))
        .or(circle.map(|c| c.center_px));
    if let Some(p) = center {
        let (x, y) = (to_px(p.x + dx), to_px(p.y));
        let arm = 5;
        for seg in [[(x - arm, y), (x + arm, y)], [(x, y - arm), (x, y + arm)]] {
            root.draw(&PathElement::new(seg.to_vec(), color.stroke_width(width)))
                .map_err(draw_err)?;
        }
    }
    if let Some(c) = circle {
        let (x, y) = (to_px(c.center_px.x + dx), to_px(c.center_px.y));
        let r = to_px(c.radius_px).max(2);
        root.draw(&Circle::new((x, y), r, color.stroke_width(width)))
            .map_err(draw_err)?;
    }
    if let (Some(b), None) = (&fruit.bbox_px, fruit.center_m) {
        let rect = [
            (to_px(b.xmin + dx), to_px(b.ymin)),
            (to_px(b.xmax + dx), to_px(b.ymax)),
        ];
        root.draw(&Rectangle::new(rect, color.stroke_width(width)))
            .map_err(draw_err)?;
    }
    Ok(())
}

/// One detection: its circle, a dot at its centre and a label (see the module docs).
fn draw_detection(
    root: &Area<'_>,
    camera: &PinholeCamera,
    d: &Detection,
    det_style: &TextStyle<'_>,
    (w, h): (u32, u32),
) -> Result<()> {
    // The detection's circle (`ImageCircle` rule: its own, its sphere projected, or its
    // box's); a bare centre gets a small marker circle.
    let circle = d.image_circle(camera);
    let Some(p) = circle
        .map(|c| c.center_px)
        .or_else(|| camera.project(&d.center_m))
    else {
        return Ok(());
    };
    let (x, y) = (to_px(p.x), to_px(p.y));
    let r = circle.map_or(NO_SIZE_RADIUS_PX, |c| to_px(c.radius_px).max(2));
    draw_ring(root, (x, y), r, DETECTION)?;
    let label = match d.diameter_m {
        Some(dm) => format!("{:.2} | ⌀{:.0} mm", d.score, dm * 1e3),
        None => format!("{:.2}", d.score),
    };
    // Centred above the circle, kept inside the image.
    draw_label(root, label, det_style, |(tw, th)| {
        (
            (x - tw / 2).clamp(0, (w as i32 - tw).max(0)),
            (y - r - th - 3).clamp(0, (h as i32 - th).max(0)),
        )
    })
}

/// `label` in `style` on a pale box, its top left corner where `place` puts it given the text's
/// size (width, height).
fn draw_label(
    root: &Area<'_>,
    label: String,
    style: &TextStyle<'_>,
    place: impl FnOnce((i32, i32)) -> (i32, i32),
) -> Result<()> {
    let (tw, th) = root.estimate_text_size(&label, style).map_err(draw_err)?;
    let (tw, th) = (tw as i32, th as i32);
    let (tx, ty) = place((tw, th));
    root.draw(&Rectangle::new(
        [(tx - 2, ty - 1), (tx + tw + 2, ty + th + 1)],
        WHITE.mix(0.7).filled(),
    ))
    .map_err(draw_err)?;
    root.draw(&Text::new(label, (tx, ty), style.clone()))
        .map_err(draw_err)?;
    Ok(())
}

/// Draws the overlay (see [`draw_overlay`]) and writes it as a PNG (atomically).
///
/// # Errors
/// Drawing errors and the PNG writer's errors naming `path`.
pub fn write_overlay(
    path: &Path,
    image: &ColorImage,
    camera: &PinholeCamera,
    truth: Option<&FrameTruth>,
    detections: &[Detection],
    min_visibility: f64,
    title: &str,
) -> Result<()> {
    let img = draw_overlay(image, camera, truth, detections, min_visibility, title)?;
    pomona_io::write_color_png(path, &img)?;
    Ok(())
}

/// Colour of a pair made by the pass over the relaxation's leftovers.
const LEFTOVER_PAIR: RGBColor = RGBColor(255, 170, 0);
/// Colour of a circle that no pair uses.
const UNPAIRED: RGBColor = RGBColor(235, 235, 235);

/// The two shots of a stereo frame side by side (primary left, stereo right): each view's truth
/// circles (green, as [`draw_overlay`]), its circles (white when unpaired), and a line from each
/// located pair's primary circle to its stereo circle (red from the relaxation, orange from the
/// pass over its leftovers) labelled with the located depth; written as a PNG (`pomona stereo
/// --overlay`).
///
/// # Errors
/// Images of different sizes, drawing errors and the PNG writer's errors naming `path`.
pub fn write_stereo_overlay(
    path: &Path,
    (primary, stereo): (&ColorImage, &ColorImage),
    camera: &PinholeCamera,
    truth: (Option<&FrameTruth>, Option<&FrameTruth>),
    found: &pomona::StereoFrame,
    title: &str,
) -> Result<()> {
    let (w, h) = (primary.width(), primary.height());
    if (stereo.width(), stereo.height()) != (w, h) {
        bail!(
            "drawing the stereo overlay: the views are {w}×{h} and {}×{}",
            stereo.width(),
            stereo.height()
        );
    }
    let mut both = Vec::with_capacity(6 * (w * h) as usize);
    for (a, b) in primary
        .as_rgb()
        .chunks_exact(3 * w as usize)
        .zip(stereo.as_rgb().chunks_exact(3 * w as usize))
    {
        both.extend_from_slice(a);
        both.extend_from_slice(b);
    }
    let canvas = ColorImage::from_rgb(2 * w, h, both)
        .map_err(|e| anyhow!("drawing the stereo overlay: {e}"))?;
    // The stereo view is drawn a view's width to the right.
    let shift = f64::from(w);
    let img = draw_on(&canvas, title, |root| {
        for (view, dx) in [(truth.0, 0.0), (truth.1, shift)] {
            for fruit in view.map(|t| t.fruits.as_slice()).unwrap_or_default() {
                draw_truth(root, camera, fruit, 0.0, dx)?;
            }
        }
        let paired = |view: usize, i: usize| {
            found.pairs.iter().any(|p| {
                if view == 0 {
                    p.primary == i
                } else {
                    p.stereo == i
                }
            })
        };
        for (view, detections, dx) in [(0, &found.primary, 0.0), (1, &found.stereo, shift)] {
            for (i, d) in detections.iter().enumerate() {
                let (Some(c), Some(r)) = (d.center_px, d.radius_px) else {
                    continue;
                };
                let color = if paired(view, i) { DETECTION } else { UNPAIRED };
                draw_ring(root, (to_px(c.x + dx), to_px(c.y)), to_px(r).max(2), color)?;
            }
        }
        let style = ("sans-serif", 13).into_font().color(&BLACK);
        for pair in &found.pairs {
            let color = if pair.from_leftovers {
                LEFTOVER_PAIR
            } else {
                DETECTION
            };
            let from = (to_px(pair.primary_px.x), to_px(pair.primary_px.y));
            let to = (
                to_px(pair.stereo_circle_px.x + shift),
                to_px(pair.stereo_circle_px.y),
            );
            root.draw(&PathElement::new(vec![from, to], color.stroke_width(1)))
                .map_err(draw_err)?;
            let label = format!("{:.2} m", pair.center_m.z);
            draw_label(root, label, &style, |_| (from.0 + 4, from.1 + 4))?;
        }
        Ok(())
    })?;
    pomona_io::write_color_png(path, &img)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use pomona_core::nalgebra::Point3;

    #[test]
    fn draws_truth_green_and_detections_red_where_they_project() {
        let cam = PinholeCamera::new(200, 150, 200.0, 200.0, 100.0, 75.0).unwrap();
        let img = ColorImage::filled(200, 150, [0, 0, 0]);
        let truth: FrameTruth = serde_json::from_value(serde_json::json!({
            "complete": true,
            "fruits": [{"id": "1", "kind": "apple", "center_m": [0.0, 0.0, 1.0],
                        "diameter_m": 0.2, "visibility": 1.0}]
        }))
        .unwrap();
        let det = Detection {
            diameter_m: Some(0.1),
            ..Detection::new(Point3::new(0.25, 0.0, 1.0), 1.5)
        };
        let out = draw_overlay(&img, &cam, Some(&truth), &[det], 0.5, "test").unwrap();
        // Truth circle: centre (100, 75), radius 200 · 0.1 / 1 = 20 px → (120, 75) is on it.
        let on_truth =
            (118..=122).any(|u| out.get(u, 75).is_some_and(|c| c[1] > 150 && c[0] < 100));
        assert!(on_truth, "no green at the truth circle");
        // Detection circle: centre (150, 75), radius 10 → (160, 75).
        let on_det = (158..=162).any(|u| out.get(u, 75).is_some_and(|c| c[0] > 150 && c[1] < 100));
        assert!(on_det, "no red at the detection circle");
        assert_eq!(out.get(10, 140), Some([0, 0, 0]), "background untouched");
    }
}
