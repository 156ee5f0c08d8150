//! Log-log line plots as hand-written SVG: error against time, one labelled line per
//! estimator, with an optional horizontal floor (the reference's own noise).

use std::fmt::Write;

/// One labelled line of (x, y) points; non-positive values are skipped (log axes).
#[derive(Clone, Debug)]
pub struct Series {
    pub label: String,
    pub points: Vec<(f64, f64)>,
}

/// A horizontal line across the plot, with its label.
#[derive(Clone, Debug)]
pub struct Floor {
    pub label: String,
    pub y: f64,
}

const W: f64 = 640.0;
const H: f64 = 420.0;
const LEFT: f64 = 80.0;
const RIGHT: f64 = 150.0;
const TOP: f64 = 40.0;
const BOTTOM: f64 = 55.0;
const COLOURS: [&str; 8] = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#17becf", "#8c564b", "#e377c2"];

/// Render a log-log plot to an SVG string.
pub fn log_log_svg(title: &str, x_label: &str, y_label: &str, series: &[Series], floors: &[Floor]) -> String {
    let pts = || series.iter().flat_map(|s| s.points.iter()).filter(|p| p.0 > 0.0 && p.1 > 0.0 && p.0.is_finite() && p.1.is_finite());
    let floor_ys = floors.iter().map(|f| f.y).filter(|y| *y > 0.0 && y.is_finite());
    let (mut x0, mut x1) = pts().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| (a.min(p.0), b.max(p.0)));
    let (mut y0, mut y1) = pts().map(|p| p.1).chain(floor_ys).fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), y| (a.min(y), b.max(y)));
    if !x0.is_finite() {
        (x0, x1, y0, y1) = (1.0, 10.0, 1.0, 10.0);
    }
    // Whole decades around the data.
    let (lx0, lx1) = (x0.log10().floor(), x1.log10().ceil().max(x0.log10().floor() + 1.0));
    let (ly0, ly1) = (y0.log10().floor(), y1.log10().ceil().max(y0.log10().floor() + 1.0));
    let px = |x: f64| LEFT + (x.log10() - lx0) / (lx1 - lx0) * (W - LEFT - RIGHT);
    let py = |y: f64| H - BOTTOM - (y.log10() - ly0) / (ly1 - ly0) * (H - TOP - BOTTOM);

    let mut svg = String::new();
    let _ = writeln!(svg, r#"<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" font-family="sans-serif" font-size="12">"#);
    let _ = writeln!(svg, r#"<rect width="100%" height="100%" fill="white"/>"#);
    let _ = writeln!(svg, r#"<text x="{}" y="22" text-anchor="middle" font-size="14">{}</text>"#, (LEFT + W - RIGHT) / 2.0, escape(title));
    // Grid and decade labels.
    for d in lx0 as i32..=lx1 as i32 {
        let x = px(10f64.powi(d));
        let _ = writeln!(svg, r##"<line x1="{x:.1}" y1="{TOP}" x2="{x:.1}" y2="{:.1}" stroke="#ddd"/>"##, H - BOTTOM);
        let _ = writeln!(svg, r#"<text x="{x:.1}" y="{:.1}" text-anchor="middle">1e{d}</text>"#, H - BOTTOM + 16.0);
    }
    for d in ly0 as i32..=ly1 as i32 {
        let y = py(10f64.powi(d));
        let _ = writeln!(svg, r##"<line x1="{LEFT}" y1="{y:.1}" x2="{:.1}" y2="{y:.1}" stroke="#ddd"/>"##, W - RIGHT);
        let _ = writeln!(svg, r#"<text x="{:.1}" y="{:.1}" text-anchor="end">1e{d}</text>"#, LEFT - 6.0, y + 4.0);
    }
    let _ = writeln!(svg, r##"<rect x="{LEFT}" y="{TOP}" width="{:.1}" height="{:.1}" fill="none" stroke="#333"/>"##, W - LEFT - RIGHT, H - TOP - BOTTOM);
    let _ = writeln!(svg, r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">{}</text>"#, (LEFT + W - RIGHT) / 2.0, H - 12.0, escape(x_label));
    let _ = writeln!(
        svg,
        r#"<text x="18" y="{:.1}" text-anchor="middle" transform="rotate(-90 18 {:.1})">{}</text>"#,
        (TOP + H - BOTTOM) / 2.0,
        (TOP + H - BOTTOM) / 2.0,
        escape(y_label)
    );
    // Floors, dashed grey.
    for f in floors.iter().filter(|f| f.y > 0.0 && f.y.is_finite()) {
        let y = py(f.y);
        let _ = writeln!(svg, r##"<line x1="{LEFT}" y1="{y:.1}" x2="{:.1}" y2="{y:.1}" stroke="#666" stroke-dasharray="6 4"/>"##, W - RIGHT);
        let _ = writeln!(svg, r##"<text x="{:.1}" y="{:.1}" fill="#666">{}</text>"##, W - RIGHT + 6.0, y + 4.0, escape(&f.label));
    }
    // Lines with markers, and the legend.
    for (i, s) in series.iter().enumerate() {
        let colour = COLOURS[i % COLOURS.len()];
        let path: Vec<String> = s.points.iter().filter(|p| p.0 > 0.0 && p.1 > 0.0).map(|p| format!("{:.1},{:.1}", px(p.0), py(p.1))).collect();
        if !path.is_empty() {
            let _ = writeln!(svg, r#"<polyline fill="none" stroke="{colour}" stroke-width="2" points="{}"/>"#, path.join(" "));
            for p in &path {
                let (x, y) = p.split_once(',').unwrap_or(("0", "0"));
                let _ = writeln!(svg, r#"<circle cx="{x}" cy="{y}" r="2.5" fill="{colour}"/>"#);
            }
        }
        let ly = TOP + 14.0 + 18.0 * i as f64;
        let _ =
            writeln!(svg, r#"<line x1="{:.1}" y1="{ly:.1}" x2="{:.1}" y2="{ly:.1}" stroke="{colour}" stroke-width="2"/>"#, W - RIGHT + 8.0, W - RIGHT + 28.0);
        let _ = writeln!(svg, r#"<text x="{:.1}" y="{:.1}">{}</text>"#, W - RIGHT + 34.0, ly + 4.0, escape(&s.label));
    }
    svg.push_str("</svg>\n");
    svg
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plot_contains_every_series_and_the_floor() {
        let s = [
            Series { label: "pt".into(), points: vec![(1.0, 0.1), (2.0, 0.05), (4.0, 0.025)] },
            Series { label: "bdpt <x>".into(), points: vec![(1.0, 0.2), (2.0, 0.0), (4.0, 0.04)] },
        ];
        let svg = log_log_svg("t", "seconds", "relMSE", &s, &[Floor { label: "reference noise".into(), y: 1e-4 }]);
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        assert_eq!(svg.matches("<polyline").count(), 2);
        assert!(svg.contains("bdpt &lt;x&gt;") && svg.contains("reference noise") && svg.contains("1e-4"));
        // The zero value is skipped, not drawn at -inf.
        assert!(!svg.contains("NaN") && !svg.contains("inf"));
    }
}
