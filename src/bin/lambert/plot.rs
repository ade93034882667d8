//! Benchmark plots (plotters), each written as PNG and SVG: error against
//! time with the Pareto front marked, and time per ray against triangle
//! count.

use std::path::Path;
use std::sync::Once;

use plotters::coord::Shift;
use plotters::element::{Drawable, IntoDynElement, PointCollection};
use plotters::prelude::*;

use lambert::bench::{LadderRow, Path32, Point};
use lambert::error::{Error, Result};
use lambert::output::write_atomically;
use lambert::scene::Intersect;

const SIZE: (u32, u32) = (900, 600);

/// plotters draws text with a font we ship, so that plots look the same on
/// every machine and need no system font library.
fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        let font = include_bytes!("../../../assets/fonts/DejaVuSans.ttf");
        // A font that ships inside the binary always parses.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, font);
    });
}

fn plot_error(e: impl std::fmt::Display) -> Error {
    Error::Usage(format!("plotting: {e}"))
}

/// Draws with `draw` into `stem.png` and `stem.svg`, each written atomically.
fn png_and_svg(
    stem: &Path,
    draw_svg: impl FnOnce(DrawingArea<SVGBackend, Shift>) -> Result<()>,
    draw_png: impl FnOnce(DrawingArea<BitMapBackend, Shift>) -> Result<()>,
) -> Result<()> {
    register_font();
    let mut svg = String::new();
    draw_svg(SVGBackend::with_string(&mut svg, SIZE).into_drawing_area())?;
    write_atomically(&stem.with_extension("svg"), svg.as_bytes())?;
    let mut rgb = vec![0u8; (SIZE.0 * SIZE.1 * 3) as usize];
    draw_png(BitMapBackend::with_buffer(&mut rgb, SIZE).into_drawing_area())?;
    let image = lambert::output::encode_png_rgb8(SIZE.0, SIZE.1, &rgb)?;
    write_atomically(&stem.with_extension("png"), &image)
}

/// `png_and_svg` with one drawing, `|area| { … }`, for both backends (a
/// closure cannot be generic over them).
macro_rules! png_and_svg {
    ($stem:expr, |$area:ident| $draw:block) => {
        png_and_svg(
            $stem,
            |$area: DrawingArea<SVGBackend, Shift>| $draw,
            |$area: DrawingArea<BitMapBackend, Shift>| $draw,
        )
    };
}

/// A chart whose two axes are logarithmic.
type LogLogChart<'a, DB> = ChartContext<'a, DB, Cartesian2d<LogCoord<f64>, LogCoord<f64>>>;

/// An axis: its range, its name and how its ticks are labelled.
type Axis<'f> = (std::ops::Range<f64>, &'f str, &'f dyn Fn(&f64) -> String);

/// A white area with a chart whose two axes are logarithmic, captioned,
/// its mesh drawn.
fn log_log_chart<'a, DB: DrawingBackend + 'a>(
    area: &'a DrawingArea<DB, Shift>,
    caption: &str,
    (x, x_desc, x_label): Axis,
    (y, y_desc, y_label): Axis,
) -> Result<LogLogChart<'a, DB>> {
    area.fill(&WHITE).map_err(plot_error)?;
    let mut chart = ChartBuilder::on(area)
        .caption(caption, ("sans-serif", 24))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(x.log_scale(), y.log_scale())
        .map_err(plot_error)?;
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .x_label_formatter(x_label)
        .y_label_formatter(y_label)
        .y_desc(y_desc)
        .draw()
        .map_err(plot_error)?;
    Ok(chart)
}

/// `series` as markers, labelled in the legend with the same marker;
/// nothing where it is empty.
fn draw_points<'a, DB: DrawingBackend + 'a, E, L>(
    chart: &mut LogLogChart<'a, DB>,
    series: &[(f64, f64)],
    label: String,
    marker: impl Fn((f64, f64)) -> E,
    legend: impl Fn((i32, i32)) -> L + 'a,
) -> Result<()>
where
    for<'b> &'b E: PointCollection<'b, (f64, f64)>,
    E: Drawable<DB>,
    L: IntoDynElement<'a, DB, (i32, i32)>,
{
    if series.is_empty() {
        return Ok(());
    }
    chart
        .draw_series(series.iter().map(|&c| marker(c)))
        .map_err(plot_error)?
        .label(label)
        .legend(legend);
    Ok(())
}

/// The legend, then the picture handed to its backend.
fn finish<'a, DB: DrawingBackend + 'a, CT: CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    area: &DrawingArea<DB, Shift>,
    position: SeriesLabelPosition,
) -> Result<()> {
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(position)
        .draw()
        .map_err(plot_error)?;
    area.present().map_err(plot_error)
}

fn series_colour(path: Path32, intersect: Intersect) -> RGBColor {
    let base = match path {
        Path32::GpuF32 => (31, 119, 180),
        Path32::CpuF32 => (44, 160, 44),
        Path32::CpuF64 => (214, 39, 40),
    };
    let shade = match intersect {
        Intersect::Seed => 0.55,
        Intersect::MollerTrumbore => 0.8,
        Intersect::Watertight => 1.0,
    };
    let f = |c: u8| (c as f64 * shade) as u8;
    RGBColor(f(base.0), f(base.1), f(base.2))
}

/// Error (RMSE, log) against time (s, log) for one scene's points; points
/// on the Pareto front are ringed and joined.
pub fn time_vs_error(points: &[Point], stem: &Path) -> Result<()> {
    let Some(first) = points.first() else {
        return Ok(());
    };
    let title = format!("{}: error against time", first.scene);
    let floor = 1e-7;
    let bounds = |f: &dyn Fn(&Point) -> f64| {
        let lo = points.iter().map(f).fold(f64::INFINITY, f64::min);
        let hi = points.iter().map(f).fold(0.0, f64::max);
        (lo / 1.5, hi * 1.5)
    };
    let (t_lo, t_hi) = bounds(&|p| p.seconds.max(1e-6));
    let (e_lo, e_hi) = bounds(&|p| p.rmse.max(floor));
    let mut front: Vec<&Point> = points.iter().filter(|p| p.on_pareto_front).collect();
    front.sort_by(|a, b| a.seconds.total_cmp(&b.seconds));
    png_and_svg!(stem, |area| {
        let mut chart = log_log_chart(
            &area,
            &title,
            (t_lo..t_hi, "render time (s, median)", &|v| {
                format!("{v:.3}")
            }),
            (e_lo..e_hi, "RMSE against the converged reference", &|v| {
                format!("{v:.0e}")
            }),
        )?;
        for path in [Path32::GpuF32, Path32::CpuF32, Path32::CpuF64] {
            for intersect in Intersect::ALL {
                let colour = series_colour(path, intersect);
                let series: Vec<(f64, f64)> = points
                    .iter()
                    .filter(|p| {
                        p.path == path && p.intersect == intersect && p.sampling == "uniform"
                    })
                    .map(|p| (p.seconds.max(1e-6), p.rmse.max(floor)))
                    .collect();
                draw_points(
                    &mut chart,
                    &series,
                    format!("{path:?} {}", intersect.name()),
                    |c| Circle::new(c, 4, colour.filled()),
                    move |c| Circle::new(c, 4, colour.filled()),
                )?;
            }
        }
        for path in [Path32::GpuF32, Path32::CpuF32] {
            let colour = series_colour(path, Intersect::Watertight);
            let series: Vec<(f64, f64)> = points
                .iter()
                .filter(|p| p.path == path && p.sampling == "adaptive")
                .map(|p| (p.seconds.max(1e-6), p.rmse.max(floor)))
                .collect();
            draw_points(
                &mut chart,
                &series,
                format!("{path:?} adaptive"),
                |c| TriangleMarker::new(c, 7, colour.filled()),
                move |c| TriangleMarker::new(c, 7, colour.filled()),
            )?;
        }
        chart
            .draw_series(LineSeries::new(
                front
                    .iter()
                    .map(|p| (p.seconds.max(1e-6), p.rmse.max(floor))),
                BLACK.stroke_width(2),
            ))
            .map_err(plot_error)?
            .label("Pareto front")
            .legend(|(x, y)| PathElement::new([(x - 8, y), (x + 8, y)], BLACK.stroke_width(2)));
        chart
            .draw_series(front.iter().map(|p| {
                Circle::new(
                    (p.seconds.max(1e-6), p.rmse.max(floor)),
                    8,
                    BLACK.stroke_width(2),
                )
            }))
            .map_err(plot_error)?;
        finish(&mut chart, &area, SeriesLabelPosition::UpperRight)
    })
}

/// Time per ray (ns, log) against triangle count (log), one line per device
/// and ray kind.
pub fn ladder(rows: &[LadderRow], stem: &Path) -> Result<()> {
    if rows.is_empty() {
        return Ok(());
    }
    let mut devices: Vec<String> = Vec::new();
    for row in rows {
        if !devices.contains(&row.device) {
            devices.push(row.device.clone());
        }
    }
    let ns = |mrays: f64| 1e3 / mrays.max(1e-9);
    let x_lo = rows.iter().map(|r| r.triangles).min().unwrap() as f64 / 1.5;
    let x_hi = rows.iter().map(|r| r.triangles).max().unwrap() as f64 * 1.5;
    let all_ns: Vec<f64> = rows
        .iter()
        .flat_map(|r| [ns(r.primary_mrays_per_s), ns(r.shadow_mrays_per_s)])
        .collect();
    // Whole decades: the log axis labels only those it spans in full.
    let y_lo = 10f64.powf(
        all_ns
            .iter()
            .cloned()
            .fold(f64::INFINITY, f64::min)
            .log10()
            .floor(),
    );
    let y_hi = 10f64.powf(all_ns.iter().cloned().fold(0.0, f64::max).log10().ceil());
    let palette = [
        RGBColor(31, 119, 180),
        RGBColor(44, 160, 44),
        RGBColor(214, 39, 40),
        RGBColor(148, 103, 189),
    ];
    png_and_svg!(stem, |area| {
        let mut chart = log_log_chart(
            &area,
            "Time per ray against scene size",
            (x_lo..x_hi, "triangles", &|v| format!("{v:.0}")),
            (y_lo..y_hi, "ns per ray (median)", &|v| format!("{v:.0}")),
        )?;
        for (i, device) in devices.iter().enumerate() {
            let colour = palette[i % palette.len()];
            for (kind, dashed) in [("primary", false), ("shadow", true)] {
                let mut series: Vec<(f64, f64)> = rows
                    .iter()
                    .filter(|r| &r.device == device)
                    .map(|r| {
                        let m = if dashed {
                            r.shadow_mrays_per_s
                        } else {
                            r.primary_mrays_per_s
                        };
                        (r.triangles as f64, ns(m))
                    })
                    .collect();
                series.sort_by(|a, b| a.0.total_cmp(&b.0));
                let style = if dashed {
                    colour.stroke_width(1)
                } else {
                    colour.stroke_width(3)
                };
                chart
                    .draw_series(LineSeries::new(series.clone(), style))
                    .map_err(plot_error)?
                    .label(format!("{device}: {kind}"))
                    .legend(move |(x, y)| PathElement::new([(x - 8, y), (x + 8, y)], style));
                chart
                    .draw_series(series.iter().map(|&p| Circle::new(p, 4, colour.filled())))
                    .map_err(plot_error)?;
            }
        }
        finish(&mut chart, &area, SeriesLabelPosition::UpperLeft)
    })
}
