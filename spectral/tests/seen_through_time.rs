//! The seen image through time (`restauro_spectral::seen::time_course`): an eye watching a
//! sequence, checked against the published time course it implements.
//!
//! The scene is two neutral stones (reflectances 0.2 and 0.5) side by side under one light, a
//! daylight whose colour temperature and level the test sets frame by frame; the renderer's
//! adapting white is that light on a white diffuser.

use glam::DVec3;
use restauro_spectral::Xyz;
use restauro_spectral::adaptation::ConeSpace;
use restauro_spectral::illuminant::daylight_chromaticity;
use restauro_spectral::seen::time_course::{CHROMATIC_HALF_LIFE_S, cones_of};
use restauro_spectral::seen::{EyeHistory, EyeState, SeenParams, seen};

const SIZE: (usize, usize) = (48, 32);

/// The light: daylight of `cct_k` on a white diffuser at `level_cd_m2`.
fn light(cct_k: f64, level_cd_m2: f64) -> Xyz {
    daylight_chromaticity(cct_k).unwrap().to_xyz(level_cd_m2)
}

/// The render of the two stones under `light` and its adapting white.
fn frame(light: Xyz) -> (Vec<[f32; 3]>, Vec<[f32; 4]>) {
    let (w, h) = SIZE;
    let l = [light.x as f32, light.y as f32, light.z as f32];
    let xyz = (0..w * h)
        .map(|p| {
            let reflectance = if p % w < w / 2 { 0.2 } else { 0.5 };
            l.map(|v| v * reflectance)
        })
        .collect();
    let white = vec![[l[0], l[1], l[2], 2.0 * l[1]]; w * h];
    (xyz, white)
}

/// The seen image of `light` by an eye coming with `history`, and the eye after it.
fn seen_by(light: Xyz, history: Option<EyeHistory>) -> (Vec<[f32; 3]>, EyeState) {
    let (xyz, white) = frame(light);
    let params = SeenParams { history, ..SeenParams::default() };
    let (out, stats) = seen(&xyz, &white, SIZE, &params, &|_, _| {}).unwrap();
    (out, stats.eye)
}

/// The mean CAT16 cone responses of the darker stone (the left half) in a seen image.
fn stone_cones(seen: &[[f32; 3]]) -> DVec3 {
    let (w, _) = SIZE;
    let left: Vec<&[f32; 3]> =
        seen.iter().enumerate().filter(|(p, _)| p % w < w / 2).map(|(_, v)| v).collect();
    let sum = left.iter().fold(DVec3::ZERO, |s, v| {
        s + DVec3::new(f64::from(v[0]), f64::from(v[1]), f64::from(v[2]))
    });
    ConeSpace::Cat16.matrix() * (sum / left.len() as f64)
}

/// The largest change of a cone's log response from `a` to `b`.
fn log_change(a: DVec3, b: DVec3) -> f64 {
    (0..3).map(|i| (b[i] / a[i]).ln().abs()).fold(0.0, f64::max)
}

/// What the light changed from `a` to `b`: the largest change of a cone's log response of its
/// white, plus the change of its log level.
fn light_change(a: Xyz, b: Xyz) -> f64 {
    let (ca, cb) = (DVec3::from(cones_of(a)), DVec3::from(cones_of(b)));
    log_change(ca, cb) + (b.y / a.y).ln().abs()
}

/// The same light in every frame: every frame of a walk at 25 frames a second is the seen image
/// of that frame alone, bit for bit.
#[test]
fn the_same_light_in_every_frame_gives_identical_seen_frames() {
    let l = light(6500.0, 3000.0);
    let (alone, mut eye) = seen_by(l, None);
    for _ in 0..6 {
        let (out, after) = seen_by(l, Some(EyeHistory { before: eye, elapsed_s: 0.04 }));
        assert!(out == alone, "a frame under the same light differs from the frame alone");
        eye = after;
    }
}

/// The most of a frame-to-frame change of the light that a lagging eye sees: 1 − s·D with the
/// instantaneous share s = 0.5 and D > 0.9.
const MOST_OF_THE_LIGHTS_CHANGE: f64 = 0.55;

/// A light that warms from 6500 K to 4000 K and halves over a minute, seen every second, then
/// holds for seven minutes, seen every ten seconds.
///
/// - Frame to frame, the seen colour of a stone changes by at most 0.55 of what the light does
///   (the largest change of a CAT16 cone's log response, plus the change of the log level): the
///   eye takes half of any change of the light's colour at once, and its level within the
///   second, with a degree of adaptation over 0.9 at these levels, so 1 − 0.5 · 0.9 of the
///   change at most is left to be seen. The eye's lag hides part of the light's change, never
///   adds to it.
/// - An eye that lags sees more of the warming than one adapted to each frame alone.
/// - Once the light holds, what separates the lagging frame from the frame alone halves every
///   20 s (Rinner & Gegenfurtner's slow half-life), and after 400 s the frame is the frame
///   alone, bit for bit.
#[test]
fn a_slowly_changing_light_is_seen_to_change_by_what_the_light_explains() {
    let ramp: Vec<Xyz> = (0..=60)
        .map(|s| {
            let t = f64::from(s) / 60.0;
            light(6500.0 - 2500.0 * t, 2000.0 - 1000.0 * t)
        })
        .collect();
    let (first, mut eye) = seen_by(ramp[0], None);
    let mut before = stone_cones(&first);
    let mut largest_share: f64 = 0.0;
    for pair in ramp.windows(2) {
        let (out, after) = seen_by(pair[1], Some(EyeHistory { before: eye, elapsed_s: 1.0 }));
        let now = stone_cones(&out);
        let (seen_change, explained) = (log_change(before, now), light_change(pair[0], pair[1]));
        assert!(
            seen_change <= MOST_OF_THE_LIGHTS_CHANGE * explained + 1e-9,
            "the stone's seen colour changed by {seen_change:.5} between frames; the light by \
             {explained:.5}"
        );
        largest_share = largest_share.max(seen_change / explained);
        (before, eye) = (now, after);
    }
    eprintln!("frame to frame, the seen change is at most {largest_share:.3} of the light's");
    let last = *ramp.last().unwrap();
    let (alone, _) = seen_by(last, None);
    let start = stone_cones(&first);
    let (lagging, adapted) = (log_change(start, before), log_change(start, stone_cones(&alone)));
    eprintln!("over the minute: lagging eye {lagging:.4}, adapted eye {adapted:.4} (log cone)");
    assert!(
        lagging > adapted,
        "over the minute the lagging eye saw the stone change by {lagging:.4}, the eye adapted to \
         each frame by {adapted:.4}"
    );
    // The light holds: the distance to the frame alone, every 10 s.
    let alone_cones = stone_cones(&alone);
    let mut distances = vec![log_change(alone_cones, before)];
    let mut last_out = Vec::new();
    for _ in 0..42 {
        let (out, after) = seen_by(last, Some(EyeHistory { before: eye, elapsed_s: 10.0 }));
        distances.push(log_change(alone_cones, stone_cones(&out)));
        (last_out, eye) = (out, after);
    }
    // Two 10 s steps are one half-life.
    let per_half_life = 2.0 * 10.0 / CHROMATIC_HALF_LIFE_S;
    assert!((per_half_life - 1.0).abs() < 1e-12);
    for k in [0, 2, 4] {
        let ratio = distances[k + 2] / distances[k];
        eprintln!(
            "steady light, {}–{} s: the distance to the frame alone × {ratio:.3}",
            k * 10,
            k * 10 + 20
        );
        assert!((0.45..0.55).contains(&ratio), "after 20 s of steady light: {ratio:.3} of {k}");
    }
    assert!(last_out == alone, "after 420 s of steady light the frame is not the frame alone");
}

/// A frame seen by an eye coming from a much brighter light 40 ms before is darker than the
/// frame alone, and one coming from a dimmer light brighter: the level lags too (Pattanaik et
/// al.'s 80 ms), and a tenth of a second later the difference has shrunk as that time constant
/// says.
#[test]
fn the_level_lags_by_the_cones_time_constant() {
    let bright = light(6500.0, 4000.0);
    let dim = light(6500.0, 1000.0);
    let (alone, _) = seen_by(dim, None);
    let (_, bright_eye) = seen_by(bright, None);
    let (after_bright, _) = seen_by(dim, Some(EyeHistory { before: bright_eye, elapsed_s: 0.04 }));
    let (later, _) = seen_by(dim, Some(EyeHistory { before: bright_eye, elapsed_s: 0.14 }));
    let y = |img: &[[f32; 3]]| stone_cones(img).y;
    assert!(y(&after_bright) < y(&alone), "{} against {}", y(&after_bright), y(&alone));
    let (_, dim_eye) = seen_by(dim, None);
    let (after_dim, _) = seen_by(bright, Some(EyeHistory { before: dim_eye, elapsed_s: 0.04 }));
    let (bright_alone, _) = seen_by(bright, None);
    assert!(y(&after_dim) > y(&bright_alone));
    // The eye's level after 40 ms and after 140 ms; a surface is seen in proportion to the
    // light's level over the eye's, so the difference from the frame alone goes as
    // 1 − L_light / L_eye.
    let eye_level = |t: f64| 1000.0 + 3000.0 * (-t / 0.080f64).exp();
    let gap = |t: f64| 1.0 - 1000.0 / eye_level(t);
    let expected = gap(0.14) / gap(0.04);
    let shrink = (y(&alone) - y(&later)) / (y(&alone) - y(&after_bright));
    assert!(
        (shrink / expected - 1.0).abs() < 0.05,
        "the difference from the frame alone shrank to {shrink:.3} of itself in 100 ms; the \
         cones' time constant gives {expected:.3}"
    );
}
