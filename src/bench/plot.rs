//! The cost-vs-error chart as a self-contained SVG: one point per configuration (medians over
//! the groups of the run), the Pareto front drawn, presets labelled in bold.

use std::collections::BTreeMap;
use std::fmt::Write;

use super::report::{pareto_front, BenchReport};

const W: f64 = 900.0;
const H: f64 = 560.0;
const LEFT: f64 = 80.0;
const RIGHT: f64 = 220.0;
const TOP: f64 = 50.0;
const BOTTOM: f64 = 60.0;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    v[v.len() / 2]
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// "Nice" tick positions covering [lo, hi].
fn ticks(lo: f64, hi: f64) -> Vec<f64> {
    let span = (hi - lo).max(1e-12);
    let raw = span / 5.0;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| span / s <= 6.0)
        .unwrap_or(10.0 * mag);
    let mut t = (lo / step).ceil() * step;
    let mut out = Vec::new();
    while t <= hi + 1e-9 {
        out.push(t);
        t += step;
    }
    out
}

pub fn svg(report: &BenchReport) -> String {
    // Aggregate each configuration over the run's groups.
    let mut by_config: BTreeMap<String, (Vec<f64>, Vec<f64>, bool)> = BTreeMap::new();
    let mut order = Vec::new();
    for r in &report.records {
        let e = by_config.entry(r.config.clone()).or_insert_with(|| {
            order.push(r.config.clone());
            (
                Vec::new(),
                Vec::new(),
                crate::settings::Preset::from_name(&r.config).is_some(),
            )
        });
        e.0.push(r.frame_ms.median);
        e.1.push(r.errors.flip);
    }
    let points: Vec<(String, f64, f64, bool)> = order
        .iter()
        .filter_map(|name| {
            let (t, f, preset) = by_config.get(name)?;
            Some((name.clone(), median(t.clone()), median(f.clone()), *preset))
        })
        .filter(|(_, t, f, _)| t.is_finite() && f.is_finite())
        .collect();
    let mut s = String::new();
    let _ = write!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" viewBox="0 0 {W} {H}" font-family="sans-serif" font-size="12">
<rect width="100%" height="100%" fill="white"/>
<text x="{LEFT}" y="28" font-size="16" font-weight="bold">Cost vs error against the reference ({})</text>
"#,
        escape(&report.machine.adapter)
    );
    if points.is_empty() {
        s.push_str("<text x=\"100\" y=\"200\">no measurements</text></svg>\n");
        return s;
    }
    let (tmax, fmax) = points
        .iter()
        .fold((0.0f64, 0.0f64), |(a, b), p| (a.max(p.1), b.max(p.2)));
    let (tmax, fmax) = (tmax * 1.1 + 1e-9, fmax * 1.15 + 1e-4);
    let (pw, ph) = (W - LEFT - RIGHT, H - TOP - BOTTOM);
    let x = |t: f64| LEFT + t / tmax * pw;
    let y = |f: f64| TOP + ph - f / fmax * ph;
    let _ = writeln!(
        s,
        r##"<rect x="{LEFT}" y="{TOP}" width="{pw}" height="{ph}" fill="none" stroke="#444"/>"##
    );
    for t in ticks(0.0, tmax) {
        let _ = writeln!(
            s,
            r##"<line x1="{0}" y1="{1}" x2="{0}" y2="{2}" stroke="#ddd"/><text x="{0}" y="{3}" text-anchor="middle">{4}</text>"##,
            x(t),
            TOP,
            TOP + ph,
            TOP + ph + 18.0,
            t
        );
    }
    for f in ticks(0.0, fmax) {
        let _ = writeln!(
            s,
            r##"<line x1="{0}" y1="{1}" x2="{2}" y2="{1}" stroke="#ddd"/><text x="{3}" y="{4}" text-anchor="end">{5:.3}</text>"##,
            LEFT,
            y(f),
            LEFT + pw,
            LEFT - 6.0,
            y(f) + 4.0,
            f
        );
    }
    let _ = writeln!(
        s,
        r#"<text x="{}" y="{}" text-anchor="middle">frame time, ms (median; lower is cheaper)</text>"#,
        LEFT + pw / 2.0,
        H - 18.0
    );
    let _ = writeln!(
        s,
        r#"<text transform="translate(22 {}) rotate(-90)" text-anchor="middle">FLIP mean vs reference (lower is better)</text>"#,
        TOP + ph / 2.0
    );
    let coords: Vec<(f64, f64)> = points.iter().map(|p| (p.1, p.2)).collect();
    let mut front: Vec<usize> = pareto_front(&coords);
    front.sort_by(|&a, &b| coords[a].0.total_cmp(&coords[b].0));
    let path: Vec<String> = front
        .iter()
        .map(|&i| format!("{:.1},{:.1}", x(coords[i].0), y(coords[i].1)))
        .collect();
    let _ = writeln!(
        s,
        r##"<polyline points="{}" fill="none" stroke="#d62728" stroke-width="2" stroke-dasharray="6 4"/>"##,
        path.join(" ")
    );
    for (i, (name, t, f, preset)) in points.iter().enumerate() {
        let on_front = front.contains(&i);
        let colour = if *preset { "#1f77b4" } else { "#7f7f7f" };
        let _ = writeln!(
            s,
            r##"<circle cx="{:.1}" cy="{:.1}" r="{}" fill="{}" stroke="{}" stroke-width="1.5"><title>{}: {:.2} ms, FLIP {:.4}</title></circle>"##,
            x(*t),
            y(*f),
            if *preset { 6 } else { 4 },
            colour,
            if on_front { "#d62728" } else { "white" },
            escape(name),
            t,
            f
        );
        if *preset {
            let _ = writeln!(
                s,
                r#"<text x="{:.1}" y="{:.1}" font-weight="bold">{}</text>"#,
                x(*t) + 8.0,
                y(*f) - 6.0,
                escape(name)
            );
        }
    }
    // Legend: every configuration, so grey points can be identified.
    let lx = W - RIGHT + 15.0;
    let _ = writeln!(
        s,
        r#"<text x="{lx}" y="{TOP}" font-weight="bold">configurations</text>"#
    );
    for (i, (name, t, f, preset)) in points.iter().enumerate() {
        let _ = writeln!(
            s,
            r#"<text x="{lx}" y="{:.1}" font-size="10"{}>{}{} — {:.1} ms, {:.3}</text>"#,
            TOP + 16.0 + 13.0 * i as f64,
            if *preset {
                r#" font-weight="bold""#
            } else {
                ""
            },
            if front.contains(&i) { "★ " } else { "" },
            escape(name),
            t,
            f
        );
    }
    s.push_str("</svg>\n");
    s
}
