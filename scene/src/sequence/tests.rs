use super::*;
use crate::load::parse_scene;
use chrono::{NaiveDate, NaiveTime};

fn scene(lights: &str) -> SceneFile {
    let text = format!(
        r#"
format = 1
[camera]
position = [0.0, -10.0, 1.7]
target = [0.0, 0.0, 1.7]
width = 32
height = 16
[render]
samples_per_pixel = 1
[spectra]
grey = {{ constant = 0.5 }}
white = {{ illuminant = "D65" }}
[materials.stone]
model = "lambert"
reflectance = "grey"
[[objects]]
name = "ground"
mesh = "ground.obj"
materials = {{ stone = "stone" }}
[variants.as-found]
state = "degraded"
[variants.cleaned]
state = "cleaned"
[[views]]
name = "gate"
position = [0.0, -10.0, 1.7]
target = [0.0, 0.0, 1.7]
[[views]]
name = "fountain"
position = [10.0, -10.0, 1.7]
target = [0.0, 0.0, 1.7]
[[views]]
name = "steps"
position = [10.0, 0.0, 1.7]
target = [0.0, 0.0, 1.7]
{lights}
"#
    );
    parse_scene(&text, Path::new("s.toml")).unwrap()
}

const AOSTA_SUN: &str = r#"
[[lights]]
kind = "sun"
preset = "sun"
spectrum = "white"
site = { latitude_deg = 45.7371, longitude_deg = 7.3228, height_m = 583.0, datetime = "2026-07-15T15:30:00+02:00" }
[[lights]]
kind = "sky"
preset = "clear"
"#;

fn hm(h: u32, m: u32) -> NaiveTime {
    NaiveTime::from_hms_opt(h, m, 0).unwrap()
}

fn every(text: &str) -> Every {
    parse_every(text).unwrap()
}

#[test]
fn a_day_every_quarter_hour_has_its_frames_at_the_scenes_offset() {
    let s = scene(AOSTA_SUN);
    let day = Sequence::Day { date: None, from: hm(6, 0), to: hm(21, 0), every: every("15m") };
    let frames = day.frames(&s, Path::new("s.toml"), &Limits::default()).unwrap();
    // 15 hours at 4 frames an hour, both ends included.
    assert_eq!(frames.len(), 61);
    assert_eq!(frames[0].label, "06:00");
    assert_eq!(frames[0].datetime.as_deref(), Some("2026-07-15T06:00:00+02:00"));
    assert_eq!(frames[60].datetime.as_deref(), Some("2026-07-15T21:00:00+02:00"));
    assert_eq!(frames[1].label, "06:15");
    // The eye's clock: a quarter of an hour a frame.
    assert_eq!(frames[1].elapsed_s, Some(900.0));
    assert_eq!(frames[60].elapsed_s, Some(15.0 * 3600.0));
    let on = NaiveDate::from_ymd_opt(2026, 12, 21);
    let winter = Sequence::Day { date: on, from: hm(12, 0), to: hm(12, 0), every: every("1h") };
    let frames = winter.frames(&s, Path::new("s.toml"), &Limits::default()).unwrap();
    assert_eq!(frames[0].datetime.as_deref(), Some("2026-12-21T12:00:00+02:00"));
}

#[test]
fn steps_are_read_as_people_write_them_and_zero_is_refused() {
    assert_eq!(every("15m").seconds(), 900);
    assert_eq!(every("1h30m").seconds(), 5400);
    assert_eq!(every("90s").seconds(), 90);
    for bad in ["0m", "0", "15", "m", "", "15x", "0h0m"] {
        let e = parse_every(bad).unwrap_err();
        assert!(e.contains("15m"), "{bad}: {e}");
    }
    assert!(parse_every("0m").unwrap_err().contains("zero"));
}

#[test]
fn a_range_that_never_sees_the_sun_is_refused_with_the_fix() {
    let s = scene(AOSTA_SUN);
    let night = Sequence::Day { date: None, from: hm(22, 0), to: hm(23, 30), every: every("30m") };
    let e = night.frames(&s, Path::new("s.toml"), &Limits::default()).unwrap_err().to_string();
    assert!(e.contains("the sun never rises") && e.contains("between sunrise and sunset"), "{e}");
    let backwards = Sequence::Day { date: None, from: hm(18, 0), to: hm(6, 0), every: every("1h") };
    let e = backwards.frames(&s, Path::new("s.toml"), &Limits::default()).unwrap_err();
    assert!(e.to_string().contains("backwards"), "{e}");
}

#[test]
fn a_sun_without_a_site_cannot_move() {
    let s = scene(
        r#"
[[lights]]
kind = "sun"
preset = "sun"
spectrum = "white"
azimuth_deg = 180.0
elevation_deg = 40.0
"#,
    );
    let day = Sequence::Day { date: None, from: hm(6, 0), to: hm(21, 0), every: every("1h") };
    let e = day.frames(&s, Path::new("s.toml"), &Limits::default()).unwrap_err().to_string();
    assert!(e.contains("site"), "{e}");
    let frame = Frame {
        label: "x".into(),
        datetime: Some("2026-07-15T12:00:00+02:00".into()),
        camera: None,
        variant: None,
        elapsed_s: None,
    };
    assert!(frame.apply(&mut s.clone(), Path::new("s.toml")).is_err());
}

#[test]
fn the_solstices_and_equinoxes_at_noon() {
    let s = scene(AOSTA_SUN);
    let dates = ["2026-03-20", "2026-06-21", "2026-09-23", "2026-12-21"]
        .map(|d| d.parse::<NaiveDate>().unwrap())
        .to_vec();
    let seq = Sequence::Dates { dates, at: hm(13, 0) };
    let frames = seq.frames(&s, Path::new("s.toml"), &Limits::default()).unwrap();
    assert_eq!(frames.len(), 4);
    assert_eq!(frames[3].label, "2026-12-21 13:00");
    let mut file = s.clone();
    frames[3].apply(&mut file, Path::new("s.toml")).unwrap();
    let Light::Sun { site: Some(site), .. } = &file.lights[0] else { panic!() };
    assert_eq!(site.datetime, "2026-12-21T13:00:00+02:00");
}

#[test]
fn too_many_frames_are_refused_naming_the_flag() {
    let s = scene(AOSTA_SUN);
    let day = Sequence::Day { date: None, from: hm(6, 0), to: hm(21, 0), every: every("1s") };
    let e = day.frames(&s, Path::new("s.toml"), &Limits::default()).unwrap_err().to_string();
    assert!(e.contains("--max-frames") && e.contains("54001"), "{e}");
}

/// A walk at 1.4 m/s: the frames are evenly spaced along the curve, it passes through the
/// views, and it starts at the first one.
#[test]
fn a_walk_goes_through_its_views_at_walking_pace() {
    let s = scene(AOSTA_SUN);
    let views = ["gate", "fountain", "steps"].map(String::from).to_vec();
    let walk = Sequence::Walk { views, fps: 25.0, speed_m_s: 1.4 };
    let frames = walk.frames(&s, Path::new("s.toml"), &Limits::default()).unwrap();
    let at = |f: &Frame| f.camera.as_ref().unwrap().position;
    assert_eq!(at(&frames[0]), [0.0, -10.0, 1.7]);
    assert_eq!(frames[25].elapsed_s, Some(1.0));
    // Each step is 1.4 / 25 m along the curve (the chord is a hair shorter on the bend).
    let step = 1.4 / 25.0;
    for w in frames.windows(2) {
        let d = distance(at(&w[0]), at(&w[1]));
        assert!((d - step).abs() < 0.01 * step, "{d}");
    }
    // Two legs of 10 m with a rounded corner: a little more than 20 m in all.
    let length = (frames.len() - 1) as f64 * step;
    assert!((20.0..21.5).contains(&length), "{length}");
    // The walk passes the fountain within one step.
    let nearest =
        frames.iter().map(|f| distance(at(f), [10.0, -10.0, 1.7])).fold(f64::MAX, f64::min);
    assert!(nearest < step, "{nearest}");
    assert!(frames.iter().all(|f| f.camera.as_ref().unwrap().position[2] == 1.7));
}

fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

#[test]
fn a_walk_of_one_view_or_an_unknown_view_or_no_speed_is_refused() {
    let s = scene(AOSTA_SUN);
    let walk = |views: &[&str], fps, speed_m_s| {
        let views = views.iter().map(|v| (*v).to_owned()).collect();
        Sequence::Walk { views, fps, speed_m_s }
            .frames(&s, Path::new("s.toml"), &Limits::default())
            .unwrap_err()
            .to_string()
    };
    let e = walk(&["gate"], 25.0, 1.4);
    assert!(e.contains("at least two saved views") && e.contains("`fountain`"), "{e}");
    let e = walk(&["gate", "fontain"], 25.0, 1.4);
    assert!(e.contains("did you mean `fountain`"), "{e}");
    assert!(walk(&["gate", "fountain"], 0.0, 1.4).contains("--fps"));
    assert!(walk(&["gate", "fountain"], 25.0, f64::NAN).contains("--speed"));
    assert!(walk(&["gate", "gate"], 25.0, 1.4).contains("same place"));
}

#[test]
fn hypotheses_are_one_frame_each_and_must_exist() {
    let s = scene(AOSTA_SUN);
    let seq = Sequence::Hypotheses { variants: vec!["as-found".into(), "cleaned".into()] };
    let frames = seq.frames(&s, Path::new("s.toml"), &Limits::default()).unwrap();
    assert_eq!(frames[1].variant.as_deref(), Some("cleaned"));
    let seq = Sequence::Hypotheses { variants: vec!["as-found".into(), "clean".into()] };
    let e = seq.frames(&s, Path::new("s.toml"), &Limits::default()).unwrap_err().to_string();
    assert!(e.contains("did you mean `cleaned`"), "{e}");
}

#[test]
fn a_frame_from_the_wire_is_checked() {
    let good = Frame {
        label: "06:00".into(),
        datetime: None,
        camera: None,
        variant: None,
        elapsed_s: None,
    };
    assert!(good.check(0).is_ok());
    let bad_time = Frame { datetime: Some("2026-07-15 06:00".into()), ..good.clone() };
    let e = bad_time.check(3).unwrap_err();
    assert!(e.problem.contains("frame 3 (06:00)") && e.problem.contains("RFC 3339"), "{e}");
    let pose = Pose {
        position: [0.0; 3],
        target: [f64::NAN, 0.0, 0.0],
        up: [0.0, 0.0, 1.0],
        vertical_fov_deg: 50.0,
    };
    let bad_camera = Frame { camera: Some(pose), ..good.clone() };
    assert!(bad_camera.check(0).unwrap_err().problem.contains("finite"));
    let bad_label = Frame { label: "a\u{1b}[2J".into(), ..good.clone() };
    assert!(bad_label.check(0).unwrap_err().problem.contains("control character"));
    for t in [-1.0, f64::NAN, 1e12] {
        let bad_time = Frame { elapsed_s: Some(t), ..good.clone() };
        assert!(bad_time.check(0).unwrap_err().problem.contains("elapsed_s"), "{t}");
    }
    let at = |t: f64| Frame { elapsed_s: Some(t), ..good.clone() };
    let e = check_times(&[at(0.0), at(2.0), at(1.0)]).unwrap_err();
    assert!(e.problem.contains("frame 2 is at 1 s, before frame 1"), "{e}");
    assert!(check_times(&[at(0.0), good.clone(), at(1.0)]).is_ok());
}

#[test]
fn a_sky_shaped_by_the_sun_refuses_the_times_it_is_down() {
    let s = scene(
        r#"
[[lights]]
kind = "sun"
preset = "sun"
spectrum = "white"
site = { latitude_deg = 45.7371, longitude_deg = 7.3228, height_m = 583.0, datetime = "2026-07-15T15:30:00+02:00" }
[[lights]]
kind = "sky"
illuminance_lux = 15000.0
model = "cie-general"
cie_type = 12
"#,
    );
    let day = Sequence::Day { date: None, from: hm(5, 0), to: hm(7, 0), every: every("1h") };
    let e = day.frames(&s, Path::new("s.toml"), &Limits::default()).unwrap_err().to_string();
    assert!(e.contains("at 05:00 the sun is below the horizon") && e.contains("sunrise"), "{e}");
    let later = Sequence::Day { date: None, from: hm(7, 0), to: hm(9, 0), every: every("1h") };
    assert_eq!(later.frames(&s, Path::new("s.toml"), &Limits::default()).unwrap().len(), 3);
}
