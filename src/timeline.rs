//! The per-module timeline of Figure 18: as text and as a PNG picture (dark: computing, light:
//! waiting on another module, blank: idle).

use std::fmt::Write as _;
use std::path::Path;

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

const WIDTH: usize = 1200;
const ROW: usize = 28;
const LABEL: usize = 120;
const GLYPH_W: usize = 6;

/// Draws the timeline: one row per module, time left to right.
pub fn write_png(stats: &LogStats, path: &Path) -> anyhow::Result<()> {
    let rows = stats.modules.len().max(1);
    let height = ROW * rows + 40;
    let mut img = vec![255u8; WIDTH * height * 3];
    let plot = WIDTH - LABEL - 10;
    let span = stats.span_s.max(1e-9);
    let x_of = |t: f64| LABEL + ((t / span) * plot as f64).clamp(0.0, plot as f64) as usize;
    let fill = |img: &mut [u8], x0: usize, x1: usize, y0: usize, y1: usize, rgb: [u8; 3]| {
        for y in y0..y1.min(height) {
            for x in x0..x1.max(x0 + 1).min(WIDTH) {
                let i = (y * WIDTH + x) * 3;
                img[i..i + 3].copy_from_slice(&rgb);
            }
        }
    };
    for (r, m) in stats.modules.iter().enumerate() {
        let y = 10 + r * ROW;
        fill(
            &mut img,
            LABEL,
            LABEL + plot,
            y + ROW - 3,
            y + ROW - 2,
            [200, 200, 200],
        );
        for s in &m.busy {
            fill(
                &mut img,
                x_of(s.start_s),
                x_of(s.end_s),
                y + 4,
                y + ROW - 6,
                [40, 60, 140],
            );
        }
        for s in &m.waiting {
            fill(
                &mut img,
                x_of(s.start_s),
                x_of(s.end_s),
                y + 4,
                y + ROW - 6,
                [160, 180, 230],
            );
        }
        draw_text(&mut img, WIDTH, 6, y + 8, &m.module, [0, 0, 0]);
    }
    // Time axis: a tick every tenth of the span, labelled in seconds.
    let axis_y = 10 + rows * ROW + 4;
    for k in 0..=10 {
        let t = span * k as f64 / 10.0;
        let x = x_of(t);
        fill(&mut img, x, x + 1, axis_y, axis_y + 6, [0, 0, 0]);
        let label = format!("{t:.0}s");
        let x_text = x
            .saturating_sub(label.len() * GLYPH_W / 2)
            .min(WIDTH - label.len() * GLYPH_W);
        draw_text(&mut img, WIDTH, x_text, axis_y + 10, &label, [0, 0, 0]);
    }
    let file = std::fs::File::create(path)?;
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), WIDTH as u32, height as u32);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header()?;
    writer.write_image_data(&img)?;
    Ok(())
}

/// A tiny 5x7 font for labels (digits, lower-case letters, a few signs).
fn glyph(c: char) -> [u8; 7] {
    match c.to_ascii_lowercase() {
        '0' => [14, 17, 19, 21, 25, 17, 14],
        '1' => [4, 12, 4, 4, 4, 4, 14],
        '2' => [14, 17, 1, 2, 4, 8, 31],
        '3' => [31, 2, 4, 2, 1, 17, 14],
        '4' => [2, 6, 10, 18, 31, 2, 2],
        '5' => [31, 16, 30, 1, 1, 17, 14],
        '6' => [6, 8, 16, 30, 17, 17, 14],
        '7' => [31, 1, 2, 4, 8, 8, 8],
        '8' => [14, 17, 17, 14, 17, 17, 14],
        '9' => [14, 17, 17, 15, 1, 2, 12],
        'a' => [0, 0, 14, 1, 15, 17, 15],
        'b' => [16, 16, 22, 25, 17, 17, 30],
        'c' => [0, 0, 14, 16, 16, 17, 14],
        'd' => [1, 1, 13, 19, 17, 17, 15],
        'e' => [0, 0, 14, 17, 31, 16, 14],
        'f' => [6, 9, 8, 28, 8, 8, 8],
        'g' => [0, 15, 17, 17, 15, 1, 14],
        'h' => [16, 16, 22, 25, 17, 17, 17],
        'i' => [4, 0, 12, 4, 4, 4, 14],
        'j' => [2, 0, 6, 2, 2, 18, 12],
        'k' => [16, 16, 18, 20, 24, 20, 18],
        'l' => [12, 4, 4, 4, 4, 4, 14],
        'm' => [0, 0, 26, 21, 21, 17, 17],
        'n' => [0, 0, 22, 25, 17, 17, 17],
        'o' => [0, 0, 14, 17, 17, 17, 14],
        'p' => [0, 0, 30, 17, 30, 16, 16],
        'q' => [0, 0, 13, 19, 15, 1, 1],
        'r' => [0, 0, 22, 25, 16, 16, 16],
        's' => [0, 0, 14, 16, 14, 1, 30],
        't' => [8, 8, 28, 8, 8, 9, 6],
        'u' => [0, 0, 17, 17, 17, 19, 13],
        'v' => [0, 0, 17, 17, 17, 10, 4],
        'w' => [0, 0, 17, 17, 21, 21, 10],
        'x' => [0, 0, 17, 10, 4, 10, 17],
        'y' => [0, 0, 17, 17, 15, 1, 14],
        'z' => [0, 0, 31, 2, 4, 8, 31],
        '-' => [0, 0, 0, 14, 0, 0, 0],
        '.' => [0, 0, 0, 0, 0, 12, 12],
        '_' => [0, 0, 0, 0, 0, 0, 31],
        _ => [0; 7],
    }
}

fn draw_text(img: &mut [u8], width: usize, x: usize, y: usize, text: &str, rgb: [u8; 3]) {
    for (k, c) in text.chars().enumerate() {
        let rows = glyph(c);
        for (dy, bits) in rows.iter().enumerate() {
            for dx in 0..5 {
                if bits & (1 << (4 - dx)) != 0 {
                    let (px, py) = (x + k * GLYPH_W + dx, y + dy);
                    let i = (py * width + px) * 3;
                    if px < width && i + 3 <= img.len() {
                        img[i..i + 3].copy_from_slice(&rgb);
                    }
                }
            }
        }
    }
}
