//! The plots of `clothlab bench`, each drawn twice by plotters: SVG and PNG. Text in the
//! PNGs is rasterised with ab_glyph from the Ubuntu font egui ships (epaint_default_fonts),
//! so no system font is needed.

use std::sync::Once;

use anyhow::{Result, anyhow};
use clothlab::core::timing::overhead;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::results::Results;

pub(super) const FONT: &str = "sans-serif";
static FONTS: Once = Once::new();

fn register_fonts() {
    FONTS.call_once(|| {
        // The font is built in and valid; should registering ever fail, text is dropped
        // (plotters draws nothing for an unknown font) rather than the run failing.
        let _ = plotters::style::register_font(FONT, FontStyle::Normal, epaint_default_fonts::UBUNTU_LIGHT);
    });
}

/// A fixed colour per backend (and per API for the overhead plot).
fn colour(name: &str) -> RGBColor {
    match name {
        "cpu" => RGBColor(120, 120, 120),
        "cpu-par" => RGBColor(40, 40, 40),
        "wgpu-naive" => RGBColor(120, 170, 230),
        "wgpu" => RGBColor(20, 90, 200),
        "vulkan-naive" => RGBColor(240, 150, 110),
        "vulkan" => RGBColor(200, 40, 30),
        "gl-naive" => RGBColor(130, 200, 140),
        "wgpu-gl" => RGBColor(130, 60, 170),
        _ => RGBColor(30, 150, 60),
    }
}

/// One figure, drawable on any plotters backend.
pub(super) trait Figure {
    fn size(&self) -> (u32, u32);
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static;
}

/// The figure as SVG text and PNG bytes.
pub(super) fn both(fig: &impl Figure) -> Result<(String, Vec<u8>)> {
    register_fonts();
    let (w, h) = fig.size();
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (w, h)).into_drawing_area();
        fig.draw(&root)?;
        root.present().map_err(|e| anyhow!("drawing SVG: {e}"))?;
    }
    let mut rgb = vec![0u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        fig.draw(&root)?;
        root.present().map_err(|e| anyhow!("drawing PNG: {e}"))?;
    }
    let img = image::RgbImage::from_raw(w, h, rgb).ok_or_else(|| anyhow!("PNG buffer of the wrong size"))?;
    let mut png = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)?;
    Ok((svg, png))
}

/// Every plot of `r`: (file stem, SVG text, PNG bytes).
pub fn all(r: &Results) -> Result<Vec<(String, String, Vec<u8>)>> {
    let mut out = Vec::new();
    if !r.ladder.is_empty() {
        // The ladder: one waterfall per API and size (the backends are its rungs).
        let mut keys: Vec<(String, u32)> = Vec::new();
        for c in &r.ladder {
            if !keys.contains(&(c.api.clone(), c.n)) {
                keys.push((c.api.clone(), c.n));
            }
        }
        for (api, n) in keys {
            let (svg, png) = both(&Waterfall { r, api: &api, n })?;
            out.push((format!("ladder_{api}_{n}"), svg, png));
        }
    }
    // The report's figures (a ladder's report shows them too: every rung is a cell).
    if let Some(n) = r.kernel_size() {
        let (svg, png) = both(&Kernels { r, n })?;
        out.push(("kernels".into(), svg, png));
    }
    let (svg, png) = both(&Scaling { r, fps: false })?;
    out.push(("frame_time".into(), svg, png));
    let (svg, png) = both(&Scaling { r, fps: true })?;
    out.push(("fps".into(), svg, png));
    if r.rows.iter().any(|x| x.section == "overhead") {
        let (svg, png) = both(&Overhead { r })?;
        out.push(("overhead".into(), svg, png));
    }
    Ok(out)
}

pub(super) fn err<E: std::fmt::Display>(e: E) -> anyhow::Error {
    anyhow!("plotting: {e}")
}

/// Figures 7.1–7.4: one panel per backend, a bar per kernel (median, ms per substep) and
/// a line from min to max.
struct Kernels<'a> {
    r: &'a Results,
    n: u64,
}

impl Figure for Kernels<'_> {
    fn size(&self) -> (u32, u32) {
        let panels = self.r.backends().len().max(1) as u32;
        (1200, 120 + 300 * panels.div_ceil(2))
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        root.fill(&WHITE).map_err(err)?;
        let n = self.n;
        let title = format!("Time per kernel at {n}×{n} — {}", self.r.machine);
        let root = root.titled(&title, (FONT, 22)).map_err(err)?;
        let backends = self.r.backends();
        let rows = backends.len().div_ceil(2).max(1);
        let panels = root.split_evenly((rows, 2));
        for (b, area) in backends.iter().zip(panels.iter()) {
            // Kernels and the substep, then the frame's render (ms each).
            let mut bars: Vec<(String, f64, f64, f64)> = self
                .r
                .rows
                .iter()
                .filter(|x| x.section == "kernel" && &x.backend == b && x.size == n)
                .filter(|x| !matches!(x.label.as_str(), "frame" | "cpu record" | "cpu submit"))
                .map(|x| (x.label.clone(), x.median_ns / 1e6, x.min_ns / 1e6, x.max_ns / 1e6))
                .collect();
            if let Some(x) = self.r.get("frame", b, n, "render", None) {
                bars.push(("render".into(), x.median_ns / 1e6, x.min_ns / 1e6, x.max_ns / 1e6));
            }
            if bars.is_empty() {
                continue;
            }
            // Log scale: kernels take micro- to milliseconds, a render up to seconds.
            let (floor, top) = range(bars.iter().map(|b| b.1));
            let top = top * 2.0;
            let k = bars.len() as i32;
            let mut chart = ChartBuilder::on(area)
                .caption(format!("{b} (ms, median; log scale)"), (FONT, 17))
                .margin(8)
                .x_label_area_size(28)
                .y_label_area_size(150)
                .build_cartesian_2d((floor..top).log_scale(), (0..k - 1).into_segmented())
                .map_err(err)?;
            let names: Vec<String> = bars.iter().map(|b| b.0.clone()).collect();
            chart
                .configure_mesh()
                .disable_y_mesh()
                .x_label_formatter(&|v| sig3(*v))
                .y_labels(k as usize)
                .y_label_formatter(&|v| row_name(&names, v))
                .label_style((FONT, 13))
                .draw()
                .map_err(err)?;
            let c = colour(b);
            chart
                .draw_series(bars.iter().enumerate().map(|(i, bar)| {
                    let y = k - 1 - i as i32;
                    let mut r = Rectangle::new(
                        [(floor, SegmentValue::Exact(y)), (bar.1, SegmentValue::Exact(y + 1))],
                        c.mix(if bar.0 == "substep" || bar.0 == "render" { 0.45 } else { 0.85 }).filled(),
                    );
                    r.set_margin(4, 4, 0, 0);
                    r
                }))
                .map_err(err)?;
            chart
                .draw_series(bars.iter().enumerate().map(|(i, bar)| {
                    let y = k - 1 - i as i32;
                    Text::new(
                        sig3(bar.1),
                        (bar.1 * 1.05, SegmentValue::CenterOf(y)),
                        (FONT, 12).into_font().color(&BLACK).pos(Pos::new(HPos::Left, VPos::Center)),
                    )
                }))
                .map_err(err)?;
        }
        Ok(())
    }
}

/// Figures 7.5–7.8: time per frame, or frames per second, against particles (log–log).
struct Scaling<'a> {
    r: &'a Results,
    fps: bool,
}

impl Figure for Scaling<'_> {
    fn size(&self) -> (u32, u32) {
        (1000, 640)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        root.fill(&WHITE).map_err(err)?;
        let series: Vec<(String, Vec<(f64, f64)>)> = self
            .r
            .backends()
            .into_iter()
            .map(|b| {
                let pts = self
                    .r
                    .rows
                    .iter()
                    .filter(|x| x.section == "frame" && x.backend == b && x.label == "frame")
                    .map(|x| {
                        let ms = x.median_ns / 1e6;
                        ((x.size * x.size) as f64, if self.fps { 1e3 / ms } else { ms })
                    })
                    .collect();
                (b, pts)
            })
            .collect();
        let all: Vec<(f64, f64)> = series.iter().flat_map(|s| s.1.iter().copied()).collect();
        let (x0, x1) = range(all.iter().map(|p| p.0));
        // The fps plot always shows the 60 fps line.
        let (y0, y1) = range(all.iter().map(|p| p.1).chain(self.fps.then_some(60.0)));
        let title = if self.fps { "Frames per second" } else { "Time per frame (ms)" };
        let sub = self.r.settings.substeps;
        let mut chart = ChartBuilder::on(root)
            .caption(
                format!("{title} against particles — {sub} substeps + render per frame — {}", self.r.machine),
                (FONT, 18),
            )
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc("particles (n × n)")
            .y_desc(if self.fps { "frames per second" } else { "ms per frame" })
            .x_label_formatter(&|v| count_label(*v))
            .y_label_formatter(&|v| sig3(*v))
            .label_style((FONT, 14))
            .axis_desc_style((FONT, 15))
            .draw()
            .map_err(err)?;
        if self.fps {
            // The interactive line.
            chart
                .draw_series(LineSeries::new([(x0, 60.0), (x1, 60.0)], BLACK.mix(0.3).stroke_width(1)))
                .map_err(err)?
                .label("60 fps")
                .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], BLACK.mix(0.3)));
        }
        for (b, pts) in &series {
            let c = colour(b);
            chart
                .draw_series(LineSeries::new(pts.iter().copied(), c.stroke_width(2)))
                .map_err(err)?
                .label(b.as_str())
                .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], c.stroke_width(2)));
            chart.draw_series(pts.iter().map(|&p| Circle::new(p, 4, c.filled()))).map_err(err)?;
        }
        chart
            .configure_series_labels()
            .position(if self.fps { SeriesLabelPosition::UpperRight } else { SeriesLabelPosition::UpperLeft })
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK.mix(0.3))
            .label_font((FONT, 14))
            .draw()
            .map_err(err)?;
        Ok(())
    }
}

/// "What each optimisation buys": a waterfall of the substep time down the ladder of one
/// API at one size — naive's bar from zero, then each rung's change (green: saved, red:
/// cost), the thesis preset's bar from zero at the end.
struct Waterfall<'a> {
    r: &'a Results,
    api: &'a str,
    n: u32,
}

impl Figure for Waterfall<'_> {
    fn size(&self) -> (u32, u32) {
        let rungs = self.r.ladder.iter().filter(|c| c.api == self.api && c.n == self.n).count() as u32;
        (1100, 110 + 34 * rungs.max(1))
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        root.fill(&WHITE).map_err(err)?;
        // (label, from, to, colour) per rung, ms.
        let mut bars: Vec<(String, f64, f64, RGBColor)> = Vec::new();
        let mut prev: Option<f64> = None;
        for c in self.r.ladder.iter().filter(|c| c.api == self.api && c.n == self.n) {
            let ms = self
                .r
                .get("kernel", &c.backend, self.n as u64, clothlab::core::timing::SUBSTEP, None)
                .map(|x| x.median_ns / 1e6);
            let Some(ms) = ms.filter(|_| c.skipped.is_none()) else {
                bars.push((format!("{} (skipped)", c.rung), 0.0, 0.0, WHITE));
                continue;
            };
            if c.rung.starts_with("thesis") {
                bars.push((c.rung.clone(), 0.0, ms, RGBColor(20, 90, 200)));
            } else if let Some(p) = prev {
                let col = if ms <= p { RGBColor(40, 150, 60) } else { RGBColor(200, 40, 30) };
                bars.push((c.rung.clone(), p, ms, col));
                prev = Some(ms);
            } else {
                bars.push((c.rung.clone(), 0.0, ms, RGBColor(120, 120, 120)));
                prev = Some(ms);
            }
        }
        // The state's 64 bytes per particle-substep at the memory's peak, where known.
        let floor_ms = super::results::known_peak(self.r)
            .map(|gbps| clothlab::engine::recipe::STATE_BYTES as f64 * (self.n as f64).powi(2) / gbps / 1e6);
        let top = bars.iter().map(|b| b.1.max(b.2)).chain(floor_ms).fold(0.0, f64::max).max(1e-6) * 1.25;
        let k = bars.len().max(1) as i32;
        let mut chart = ChartBuilder::on(root)
            .caption(
                format!(
                    "What each optimisation buys — {}, n = {}, ms per substep (GPU) — {}",
                    self.api, self.n, self.r.machine
                ),
                (FONT, 18),
            )
            .margin(12)
            .x_label_area_size(36)
            .y_label_area_size(230)
            .build_cartesian_2d(0.0..top, (0..k - 1).into_segmented())
            .map_err(err)?;
        let names: Vec<String> = bars.iter().map(|b| b.0.clone()).collect();
        chart
            .configure_mesh()
            .disable_y_mesh()
            .x_desc("ms per substep")
            .x_label_formatter(&|v| sig3(*v))
            .y_labels(k as usize)
            .y_label_formatter(&|v| row_name(&names, v))
            .label_style((FONT, 14))
            .axis_desc_style((FONT, 14))
            .draw()
            .map_err(err)?;
        chart
            .draw_series(bars.iter().enumerate().filter(|(_, b)| b.1 != b.2).map(|(i, b)| {
                let y = k - 1 - i as i32;
                let (lo, hi) = (b.1.min(b.2), b.1.max(b.2));
                let mut r =
                    Rectangle::new([(lo, SegmentValue::Exact(y)), (hi, SegmentValue::Exact(y + 1))], b.3.filled());
                r.set_margin(5, 5, 0, 0);
                r
            }))
            .map_err(err)?;
        chart
            .draw_series(bars.iter().enumerate().filter(|(_, b)| b.1 != b.2).map(|(i, b)| {
                let y = k - 1 - i as i32;
                let change = if b.1 > 0.0 { format!(" ({:+.0} %)", (b.2 / b.1 - 1.0) * 100.0) } else { String::new() };
                Text::new(
                    format!("{}{change}", sig3(b.2)),
                    (b.1.max(b.2) + top * 0.01, SegmentValue::CenterOf(y)),
                    (FONT, 13).into_font().color(&BLACK).pos(Pos::new(HPos::Left, VPos::Center)),
                )
            }))
            .map_err(err)?;
        if let Some(f) = floor_ms {
            let style = ShapeStyle::from(&RGBColor(200, 40, 30)).stroke_width(2);
            chart
                .draw_series(std::iter::once(PathElement::new(
                    vec![(f, SegmentValue::Exact(0)), (f, SegmentValue::Exact(k))],
                    style,
                )))
                .map_err(err)?
                .label(format!(
                    "bound: {} B per particle-substep at the memory's peak",
                    clothlab::engine::recipe::STATE_BYTES
                ))
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], style));
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::UpperRight)
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .label_font((FONT, 13))
                .draw()
                .map_err(err)?;
        }
        Ok(())
    }
}

/// The name of the horizontal bar at segment `v` of a chart listing `names` top down.
fn row_name(names: &[String], v: &SegmentValue<i32>) -> String {
    match v {
        SegmentValue::CenterOf(i) | SegmentValue::Exact(i) => usize::try_from(*i)
            .ok()
            .and_then(|i| names.len().checked_sub(1 + i))
            .and_then(|j| names.get(j).cloned())
            .unwrap_or_default(),
        SegmentValue::Last => String::new(),
    }
}

/// A count for an axis: 1000 → "1k", 250000 → "250k", 4194304 → "4.2M".
fn count_label(v: f64) -> String {
    if v >= 1e6 {
        format!("{}M", sig3(v / 1e6))
    } else if v >= 1e3 {
        format!("{}k", sig3(v / 1e3))
    } else {
        sig3(v)
    }
}

/// `v` with three significant digits, trailing zeros dropped.
fn sig3(v: f64) -> String {
    let digits = (2 - v.abs().max(1e-12).log10().floor() as i32).clamp(0, 6) as usize;
    let s = format!("{v:.digits$}");
    if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.').to_owned() } else { s }
}

/// A log-scale range around `v` (a decade's tenth of room on each side).
fn range(v: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = v.filter(|x| x.is_finite() && *x > 0.0).fold((f64::MAX, f64::MIN), |(a, b), x| (a.min(x), b.max(x)));
    if lo > hi {
        return (1.0, 10.0);
    }
    let (lo, hi) = (lo / 1.4, hi * 1.4);
    if hi / lo < 10.0 { (lo / 2.0, hi * 2.0) } else { (lo, hi) }
}

/// API overhead: the dispatch chain (time against k) and upload/readback latency (time
/// against bytes), wgpu and Vulkan side by side.
struct Overhead<'a> {
    r: &'a Results,
}

impl Figure for Overhead<'_> {
    fn size(&self) -> (u32, u32) {
        (1300, 560)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        root.fill(&WHITE).map_err(err)?;
        let root = root.titled(&format!("API overhead per stack — {}", self.r.machine), (FONT, 20)).map_err(err)?;
        let halves = root.split_evenly((1, 2));
        let rows = |api: &str, label: &str, clock: &str| -> Vec<(f64, f64)> {
            self.r
                .rows
                .iter()
                .filter(|x| x.section == "overhead" && x.backend == api && x.label == label && x.clock == clock)
                // Transfers in KiB, so that the log axis's decades are round sizes.
                .map(|x| {
                    let size = if x.label == overhead::CHAIN { x.size as f64 } else { x.size as f64 / 1024.0 };
                    (size, x.median_ns / 1e3)
                })
                .collect()
        };
        // Every stack measured, in the order measured (wgpu, wgpu-gl, vulkan, gl).
        let mut apis: Vec<&str> = Vec::new();
        for x in self.r.rows.iter().filter(|x| x.section == "overhead") {
            if !apis.contains(&x.backend.as_str()) {
                apis.push(&x.backend);
            }
        }
        // (caption, x axis, [(benchmark, clock)]) per panel.
        type Panel<'s> = (&'s str, &'s str, Vec<(&'s str, &'s str)>);
        let panels: [Panel; 2] = [
            (
                "chain of k dependent dispatches (µs)",
                "k dispatches",
                vec![
                    (overhead::CHAIN, overhead::GPU),
                    (overhead::CHAIN, overhead::CPU_RECORD),
                    (overhead::CHAIN, overhead::CPU_SUBMIT_WAIT),
                ],
            ),
            (
                "upload / readback latency (µs)",
                "KiB",
                vec![(overhead::UPLOAD, overhead::CPU_TOTAL), (overhead::READBACK, overhead::CPU_TOTAL)],
            ),
        ];
        for ((caption, xdesc, what), area) in panels.iter().zip(halves.iter()) {
            let mut series = Vec::new();
            for &api in &apis {
                for (i, (label, clock)) in what.iter().enumerate() {
                    let pts = rows(api, label, clock);
                    if !pts.is_empty() {
                        series.push((format!("{api} {label} {clock}"), api, i, pts));
                    }
                }
            }
            if series.is_empty() {
                continue;
            }
            let all: Vec<(f64, f64)> = series.iter().flat_map(|s| s.3.iter().copied()).collect();
            let (x0, x1) = range(all.iter().map(|p| p.0));
            let (y0, y1) = range(all.iter().map(|p| p.1));
            let mut chart = ChartBuilder::on(area)
                .caption(*caption, (FONT, 16))
                .margin(10)
                .x_label_area_size(40)
                .y_label_area_size(60)
                .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
                .map_err(err)?;
            chart
                .configure_mesh()
                .x_desc(*xdesc)
                .x_label_formatter(&|v| count_label(*v))
                .y_label_formatter(&|v| sig3(*v))
                .label_style((FONT, 13))
                .axis_desc_style((FONT, 14))
                .draw()
                .map_err(err)?;
            for (name, api, i, pts) in &series {
                let c = colour(api);
                let style = ShapeStyle { color: c.mix([1.0, 0.7, 0.45][*i % 3]), filled: false, stroke_width: 2 };
                chart
                    .draw_series(LineSeries::new(pts.iter().copied(), style))
                    .map_err(err)?
                    .label(name.as_str())
                    .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], style));
                chart.draw_series(pts.iter().map(|&p| Circle::new(p, 3, style.filled()))).map_err(err)?;
            }
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::UpperLeft)
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK.mix(0.3))
                .label_font((FONT, 12))
                .draw()
                .map_err(err)?;
        }
        Ok(())
    }
}
