//! The per-module timeline of a traffic log, as in the report's Figure 18: as text
//! ([`text`]) and as a PNG picture ([`picture`], [`write_png`]; dark: computing, light:
//! waiting on another module, blank: idle). The breakdown itself is `tca_logs::stats`.
//!
//! # Layout
//!
//! One file: [`text`], then [`picture`] and [`write_png`] on a `tca_canvas::Canvas`.

use std::fmt::Write as _;
use std::path::Path;

use tca_canvas::{Canvas, CanvasError, Rgb, font};
use tca_logs::LogStats;

/// The breakdown as a text table.
pub fn text(stats: &LogStats, steps: usize) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "span {:.1} s, {} messages delivered",
        stats.span_s, stats.messages
    );
    if steps > 0 {
        let _ = writeln!(
            out,
            "{steps} steps, {:.1} messages per step",
            stats.messages as f64 / steps as f64
        );
    }
    let _ = writeln!(
        out,
        "\n{:<14} {:>8} {:>12} {:>12} {:>12}",
        "module", "handled", "computing s", "waiting s", "idle s"
    );
    for m in &stats.modules {
        let _ = writeln!(
            out,
            "{:<14} {:>8} {:>12.2} {:>12.2} {:>12.2}",
            m.module, m.handled, m.computing_s, m.waiting_s, m.idle_s
        );
    }
    if !stats.queries.is_empty() {
        let _ = writeln!(
            out,
            "\n{:<22} {:>7} {:>10} {:>10}",
            "query", "count", "p50 ms", "max ms"
        );
        for q in &stats.queries {
            let _ = writeln!(
                out,
                "{:<22} {:>7} {:>10.3} {:>10.3}",
                q.name, q.count, q.p50_ms, q.max_ms
            );
        }
    }
    out
}

const WIDTH: u32 = 1200;
const ROW: i64 = 28;
const LABEL: i64 = 120;
const COMPUTING: Rgb = [40, 60, 140];
const WAITING: Rgb = [160, 180, 230];
const BASELINE: Rgb = [200, 200, 200];
const INK: Rgb = [0, 0, 0];

/// Draws the timeline: one row per module, time left to right, a tick every tenth of the span.
pub fn picture(stats: &LogStats) -> Canvas {
    let rows = stats.modules.len().max(1) as i64;
    let height = ROW * rows + 40;
    let mut pic = Canvas::new(WIDTH, height as u32, [255, 255, 255]);
    let plot = i64::from(WIDTH) - LABEL - 10;
    let span = stats.span_s.max(1e-9);
    let x_of = |t: f64| LABEL + ((t / span) * plot as f64).clamp(0.0, plot as f64) as i64;
    let bar = |pic: &mut Canvas, x0: i64, x1: i64, y: i64, c: Rgb| {
        pic.fill_rect(x0, y + 4, (x1 - x0).max(1), ROW - 10, c);
    };
    for (r, m) in stats.modules.iter().enumerate() {
        let y = 10 + r as i64 * ROW;
        pic.fill_rect(LABEL, y + ROW - 3, plot, 1, BASELINE);
        for s in &m.busy {
            bar(&mut pic, x_of(s.start_s), x_of(s.end_s), y, COMPUTING);
        }
        for s in &m.waiting {
            bar(&mut pic, x_of(s.start_s), x_of(s.end_s), y, WAITING);
        }
        pic.text(6, y + 8, &m.module, 1, INK);
    }
    let axis_y = 10 + rows * ROW + 4;
    for k in 0..=10 {
        let t = span * f64::from(k) / 10.0;
        let x = x_of(t);
        pic.fill_rect(x, axis_y, 1, 6, INK);
        let label = format!("{t:.0}s");
        let w = i64::from(font::text_width(&label, 1));
        let x_text = (x - w / 2).clamp(0, i64::from(WIDTH) - w);
        pic.text(x_text, axis_y + 10, &label, 1, INK);
    }
    pic
}

/// Draws the timeline to a PNG file.
pub fn write_png(stats: &LogStats, path: &Path) -> Result<(), CanvasError> {
    picture(stats).write_png(path)
}

#[cfg(test)]
mod tests {
    use super::*;
    use tca_logs::{ModuleStats, Span};

    fn stats() -> LogStats {
        LogStats {
            span_s: 10.0,
            messages: 4,
            modules: vec![ModuleStats {
                module: "planner".into(),
                handled: 2,
                computing_s: 2.0,
                waiting_s: 1.0,
                idle_s: 7.0,
                busy: vec![Span {
                    start_s: 0.0,
                    end_s: 2.0,
                }],
                waiting: vec![Span {
                    start_s: 5.0,
                    end_s: 6.0,
                }],
            }],
            queries: Vec::new(),
            by_name: Default::default(),
        }
    }

    #[test]
    fn computing_and_waiting_are_drawn_where_they_happened() {
        let pic = picture(&stats());
        let plot = f64::from(WIDTH) - LABEL as f64 - 10.0;
        let x = |t: f64| (LABEL as f64 + t / 10.0 * plot) as u32;
        let y = 10 + ROW as u32 / 2;
        assert_eq!(pic.pixel(x(1.0), y), Some(COMPUTING));
        assert_eq!(pic.pixel(x(5.5), y), Some(WAITING));
        assert_eq!(pic.pixel(x(8.0), y), Some([255, 255, 255]), "idle");
    }

    #[test]
    fn the_table_lists_every_module() {
        let t = text(&stats(), 2);
        assert!(t.contains("planner"), "{t}");
        assert!(t.contains("2 steps"), "{t}");
    }
}
