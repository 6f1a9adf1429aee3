//! The Retinex, and the seen image that adapts to the known light, add nothing of their own: a
//! flat noisy field stays flat (no pattern of the paths, no loss of lightness), and a rotated
//! image gives the rotated result.

use restauro_spectral::appearance::{ChannelSpace, d65_white, retinex_xyz};
use restauro_spectral::keyed_random::KeyedRng;
use restauro_spectral::retinex::RetinexParams;
use restauro_spectral::seen::{SeenParams, seen};

/// A standard normal draw (the sum of twelve uniforms, minus six).
fn normal(rng: &mut KeyedRng) -> f32 {
    (0..12).map(|_| rng.next_f32()).sum::<f32>() - 6.0
}

/// A D65 grey of luminance 40 cd/m² with `noise` relative white noise, independent per pixel
/// and channel.
fn noisy_grey(w: usize, h: usize, noise: f32, seed: u64) -> Vec<[f32; 3]> {
    let white = d65_white();
    let mut rng = KeyedRng::new(seed);
    (0..w * h)
        .map(|_| {
            let mut p = [0f32; 3];
            for (c, v) in [white.x, white.y, white.z].into_iter().enumerate() {
                p[c] = 40.0 * v as f32 * (1.0 + noise * normal(&mut rng));
            }
            p
        })
        .collect()
}

/// The periodogram |DFT|² of an n×n image (mean removed), by separable direct DFT.
fn periodogram(values: &[f64], n: usize) -> Vec<f64> {
    let mean = values.iter().sum::<f64>() / values.len() as f64;
    let (cos, sin): (Vec<f64>, Vec<f64>) = (0..n)
        .map(|k| {
            let a = std::f64::consts::TAU * k as f64 / n as f64;
            (a.cos(), -a.sin())
        })
        .unzip();
    let dft = |row: &[(f64, f64)]| -> Vec<(f64, f64)> {
        (0..n)
            .map(|k| {
                row.iter().enumerate().fold((0.0, 0.0), |(re, im), (x, &(a, b))| {
                    let (c, s) = (cos[(k * x) % n], sin[(k * x) % n]);
                    (re + a * c - b * s, im + a * s + b * c)
                })
            })
            .collect()
    };
    let rows: Vec<Vec<(f64, f64)>> = (0..n)
        .map(|y| {
            dft(&values[y * n..(y + 1) * n].iter().map(|v| (v - mean, 0.0)).collect::<Vec<_>>())
        })
        .collect();
    let mut power = vec![0.0; n * n];
    for kx in 0..n {
        let column: Vec<(f64, f64)> = (0..n).map(|y| rows[y][kx]).collect();
        for (ky, (re, im)) in dft(&column).into_iter().enumerate() {
            power[ky * n + kx] = re * re + im * im;
        }
    }
    power
}

/// The periodogram averaged over 4×4 blocks of frequencies (the zero frequency's block left
/// out): the largest block relative to the median block. For white noise each block is the
/// mean of 16 exponential variables, so among 1023 blocks the largest stands about 1.8 times
/// above the median; a pattern of lines or blotches stands far above.
fn peak_to_median(values: &[f64], n: usize) -> f64 {
    let power = periodogram(values, n);
    let mut blocks = Vec::new();
    for by in 0..n / 4 {
        for bx in 0..n / 4 {
            if bx == 0 && by == 0 {
                continue;
            }
            let mut sum = 0.0;
            for y in 0..4 {
                for x in 0..4 {
                    sum += power[(4 * by + y) * n + 4 * bx + x];
                }
            }
            blocks.push(sum / 16.0);
        }
    }
    blocks.sort_by(f64::total_cmp);
    blocks[blocks.len() - 1] / blocks[blocks.len() / 2]
}

#[test]
fn a_flat_noisy_field_stays_flat_and_white() {
    let n = 128;
    let input = noisy_grey(n, n, 0.03, 1);
    let params = RetinexParams { seed: 3, ..Default::default() };
    let (out, _) = retinex_xyz(&input, n, n, &params, ChannelSpace::default(), &|_, _| {}).unwrap();
    let y_in: Vec<f64> = input.iter().map(|p| f64::from(p[1])).collect();
    let y_out: Vec<f64> = out.iter().map(|p| f64::from(p[1])).collect();
    // The field is its own white: the mean lightness is 1 within 1 %.
    let mean = y_out.iter().sum::<f64>() / y_out.len() as f64;
    eprintln!("mean lightness of a flat field with 3 % noise: {mean:.4}");
    assert!((mean - 1.0).abs() < 0.01, "mean lightness {mean}");
    // No pattern: the output's spectrum has no peak that the input's noise does not have.
    let (before, after) = (peak_to_median(&y_in, n), peak_to_median(&y_out, n));
    eprintln!("peak / median of the 4×4-block periodogram: input {before:.2}, output {after:.2}");
    assert!(after < 1.5 * before.max(1.8), "input {before:.2}, output {after:.2}");
}

/// A Mondrian of rectangles of random colours and sizes with 2 % noise.
fn mondrian(n: usize, seed: u64) -> Vec<[f32; 3]> {
    let mut rng = KeyedRng::new(seed);
    let mut img = vec![[20.0f32; 3]; n * n];
    for _ in 0..60 {
        let (x0, y0) = (rng.below(n as u32) as usize, rng.below(n as u32) as usize);
        let (w, h) = (4 + rng.below(n as u32 / 3) as usize, 4 + rng.below(n as u32 / 3) as usize);
        let colour =
            [5.0 + 95.0 * rng.next_f32(), 5.0 + 95.0 * rng.next_f32(), 5.0 + 95.0 * rng.next_f32()];
        for y in y0..(y0 + h).min(n) {
            for x in x0..(x0 + w).min(n) {
                img[y * n + x] = colour;
            }
        }
    }
    img.iter().map(|p| p.map(|v| v * (1.0 + 0.02 * normal(&mut rng)))).collect()
}

/// The image turned a quarter turn: (x, y) → (n − 1 − y, x).
fn rotate<T: Copy>(img: &[T], n: usize) -> Vec<T> {
    let mut out = img.to_vec();
    for y in 0..n {
        for x in 0..n {
            out[x * n + (n - 1 - y)] = img[y * n + x];
        }
    }
    out
}

fn mean_log_difference(a: &[[f32; 3]], b: &[[f32; 3]]) -> f64 {
    let total: f64 = a
        .iter()
        .zip(b)
        .map(|(p, q)| (0..3).map(|c| (f64::from(p[c]) / f64::from(q[c])).ln().abs()).sum::<f64>())
        .sum();
    total / (3 * a.len()) as f64
}

#[test]
fn a_rotated_image_gives_the_rotated_result() {
    let n = 96;
    let img = mondrian(n, 9);
    let space = ChannelSpace::default();
    let run = |img: &[[f32; 3]], seed| {
        let params = RetinexParams { seed, paths: 40, ..Default::default() };
        retinex_xyz(img, n, n, &params, space, &|_, _| {}).unwrap().0
    };
    let turned_after = rotate(&run(&img, 1), n);
    let turned_before = run(&rotate(&img, n), 1);
    // The noise of the estimate: two seeds on the same image.
    let noise = mean_log_difference(&run(&img, 1), &run(&img, 2));
    let rotation = mean_log_difference(&turned_after, &turned_before);
    eprintln!("mean |Δ log| between seeds {noise:.4}, between rotated runs {rotation:.4}");
    assert!(rotation < 1.3 * noise, "rotation {rotation} against noise {noise}");
}

/// The seen image of `img` under a uniform D65 light whose white is 100 cd/m².
fn seen_under_d65(img: &[[f32; 3]], n: usize, seed: u64, paths: u32) -> Vec<[f32; 3]> {
    let w = d65_white();
    let white = [w.x as f32 * 100.0, 100.0, w.z as f32 * 100.0, 250.0];
    let params = SeenParams {
        retinex: RetinexParams { seed, paths, ..Default::default() },
        ..Default::default()
    };
    seen(img, &vec![white; img.len()], (n, n), &params, &|_, _| {}).unwrap().0
}

/// Adapted to the known light, a flat grey field of 40 % with 3 % noise is seen at its own
/// lightness (0.4 of white, within 1 %) — not white, as the Retinex alone sees it — with no
/// pattern of the paths.
#[test]
fn a_flat_noisy_field_is_seen_at_its_own_lightness() {
    let n = 128;
    let input = noisy_grey(n, n, 0.03, 1);
    let out = seen_under_d65(&input, n, 3, 20);
    let y_in: Vec<f64> = input.iter().map(|p| f64::from(p[1])).collect();
    let y_out: Vec<f64> = out.iter().map(|p| f64::from(p[1])).collect();
    let mean = y_out.iter().sum::<f64>() / y_out.len() as f64;
    eprintln!("mean seen lightness of a 40 % field with 3 % noise: {mean:.4}");
    assert!((mean / 0.4 - 1.0).abs() < 0.01, "mean lightness {mean}");
    let (before, after) = (peak_to_median(&y_in, n), peak_to_median(&y_out, n));
    eprintln!("peak / median of the 4×4-block periodogram: input {before:.2}, output {after:.2}");
    assert!(after < 1.5 * before.max(1.8), "input {before:.2}, output {after:.2}");
}

#[test]
fn the_seen_image_of_a_rotated_image_is_the_rotated_seen_image() {
    let n = 96;
    let img = mondrian(n, 9);
    let turned_after = rotate(&seen_under_d65(&img, n, 1, 40), n);
    let turned_before = seen_under_d65(&rotate(&img, n), n, 1, 40);
    let noise =
        mean_log_difference(&seen_under_d65(&img, n, 1, 40), &seen_under_d65(&img, n, 2, 40));
    let rotation = mean_log_difference(&turned_after, &turned_before);
    eprintln!("seen: mean |Δ log| between seeds {noise:.4}, between rotated runs {rotation:.4}");
    assert!(rotation < 1.3 * noise.max(1e-4), "rotation {rotation} against noise {noise}");
}
