//! A line chart of illuminance against time, drawn on the demo's sheet primitives: the least,
//! the mean and the most of a grid's points at each frame, with the lux axis from 0 and the
//! frames' labels along the time axis.

use restauro_demo::sheet::{BACKGROUND, INK, Rgb8, text_width};

const WIDTH: u32 = 960;
const HEIGHT: u32 = 480;
/// Room for the lux labels on the left, the time labels below, the title above.
const LEFT: u32 = 96;
const BOTTOM: u32 = 40;
const TOP: u32 = 40;
const RIGHT: u32 = 24;
const GRID: [u8; 3] = [70, 70, 70];

/// The chart's series: a name, a colour and a value (lux) at each frame.
pub struct Series<'a> {
    pub name: &'a str,
    pub colour: [u8; 3],
    pub lux: Vec<f64>,
}

/// A round top for the lux axis at or above `max`: 1, 2 or 5 times a power of ten.
fn axis_top(max: f64) -> f64 {
    if !(max > 0.0 && max.is_finite()) {
        return 1.0;
    }
    let power = 10f64.powf(max.log10().floor());
    [1.0, 2.0, 5.0, 10.0].into_iter().map(|m| m * power).find(|&t| t >= max).unwrap_or(10.0 * power)
}

/// Draws a straight line (Bresenham) from (x0, y0) to (x1, y1), two pixels thick.
fn line(img: &mut Rgb8, (x0, y0): (i64, i64), (x1, y1): (i64, i64), colour: [u8; 3]) {
    let (dx, dy) = ((x1 - x0).abs(), -(y1 - y0).abs());
    let (sx, sy) = (if x0 < x1 { 1 } else { -1 }, if y0 < y1 { 1 } else { -1 });
    let (mut x, mut y, mut err) = (x0, y0, dx + dy);
    loop {
        img.fill_rect(x, y, 2, 2, colour);
        if x == x1 && y == y1 {
            return;
        }
        let e2 = 2 * err;
        if e2 >= dy {
            err += dy;
            x += sx;
        }
        if e2 <= dx {
            err += dx;
            y += sy;
        }
    }
}

/// The chart of `series` over frames labelled `labels`, titled `title`.
pub fn chart(title: &str, labels: &[String], series: &[Series]) -> Rgb8 {
    let mut img = Rgb8::new(WIDTH, HEIGHT, BACKGROUND);
    let (plot_w, plot_h) = (WIDTH - LEFT - RIGHT, HEIGHT - TOP - BOTTOM);
    let top = axis_top(series.iter().flat_map(|s| s.lux.iter().copied()).fold(0.0, f64::max));
    let frames = labels.len().max(1);
    let x_of = |i: usize| {
        let span = (frames - 1).max(1) as f64;
        i64::from(LEFT) + (i as f64 / span * f64::from(plot_w)).round() as i64
    };
    let y_of = |lux: f64| {
        let f = (lux / top).clamp(0.0, 1.0);
        i64::from(TOP + plot_h) - (f * f64::from(plot_h)).round() as i64
    };
    img.text(12, 12, title, 2, INK);
    for k in 0..=4 {
        let lux = top * f64::from(k) / 4.0;
        let y = y_of(lux);
        img.fill_rect(i64::from(LEFT), y, plot_w, 1, GRID);
        let text = format!("{lux:.0} lx");
        img.text(i64::from(LEFT) - i64::from(text_width(&text, 1)) - 6, y - 4, &text, 1, INK);
    }
    // At most about a dozen time labels, evenly spaced.
    let step = frames.div_ceil(12);
    for (i, label) in labels.iter().enumerate().step_by(step) {
        let x = x_of(i);
        img.fill_rect(x, i64::from(TOP), 1, plot_h, GRID);
        let w = i64::from(text_width(label, 1));
        img.text(x - w / 2, i64::from(TOP + plot_h + 8), label, 1, INK);
    }
    for s in series {
        let points: Vec<(i64, i64)> =
            s.lux.iter().enumerate().map(|(i, &lux)| (x_of(i), y_of(lux))).collect();
        for pair in points.windows(2) {
            line(&mut img, pair[0], pair[1], s.colour);
        }
        if let [only] = points[..] {
            img.fill_rect(only.0 - 2, only.1 - 2, 5, 5, s.colour);
        }
    }
    let mut x = i64::from(LEFT);
    for s in series {
        img.fill_rect(x, i64::from(HEIGHT - 14), 12, 8, s.colour);
        x += 16 + i64::from(img.text(x + 16, i64::from(HEIGHT - 14), s.name, 1, INK)) + 12;
    }
    img
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_lux_axis_tops_at_a_round_number() {
        assert_eq!(axis_top(73_000.0), 100_000.0);
        assert_eq!(axis_top(1_500.0), 2_000.0);
        assert_eq!(axis_top(5.0), 5.0);
        assert_eq!(axis_top(0.0), 1.0);
    }

    /// Each series is drawn in its colour where its value puts it.
    #[test]
    fn a_series_is_drawn_where_its_values_are() {
        let labels: Vec<String> = ["06:00", "12:00", "18:00"].map(String::from).to_vec();
        let red = [230, 40, 40];
        let series = [Series { name: "mean", colour: red, lux: vec![0.0, 1000.0, 0.0] }];
        let img = chart("t", &labels, &series);
        // The peak: the middle frame at the top of the axis (1000 lx).
        let (x, y) = (LEFT + (WIDTH - LEFT - RIGHT) / 2, TOP);
        assert_eq!(img.get(x, y), red);
        // The start: the first frame at 0 lx.
        assert_eq!(img.get(LEFT, HEIGHT - BOTTOM), red);
    }
}
