//! `report.md`: the report for people, section by section — the contact sheets, the renders,
//! every image, the stones under each light, what cleaning changes on the facade and the
//! floodlit facade at night — ending with the spectral library's acknowledgement.

use super::{INNER_FRACTION, Report};
use std::fmt::Write as _;

/// The report as Markdown.
pub fn markdown(r: &Report) -> String {
    let mut s = String::new();
    introduction(&mut s, r);
    renders(&mut s, r);
    images(&mut s, r);
    stones(&mut s, r);
    cleaning(&mut s, r);
    floodlighting(&mut s, r);
    let _ = writeln!(s, "\n{}", restauro_spectral::library::ECOSTRESS_ACKNOWLEDGEMENT);
    s
}

/// The title, what the run did, and the contact sheets shown.
fn introduction(s: &mut String, r: &Report) {
    let _ = writeln!(s, "# restauro demo\n");
    let _ = writeln!(
        s,
        "{} renders on an embedded cluster of {} workers, {:.1} s in all{}. Every image below is \
         beside this report; the JSON form is `report.json` (schema `{}`).\n",
        r.renders.len(),
        r.workers,
        r.total_s,
        if r.quick { " (`--quick`: small images, few samples)" } else { "" },
        r.schema
    );
    let _ = writeln!(s, "## Contact sheets\n");
    for i in r.images.iter().filter(|i| i.file.starts_with("sheets/")) {
        let _ = writeln!(s, "### {}\n\n![{}]({})\n", i.what, i.what, i.file);
    }
}

/// Every render: its scene, hypothesis, lights, parameters and time; then how it was seen.
fn renders(s: &mut String, r: &Report) {
    let _ = writeln!(s, "## Renders\n");
    let _ = writeln!(
        s,
        "| render | scene | variant | lights | integrator | size | spp | max depth | render time |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---:|---:|---:|");
    for x in &r.renders {
        let _ = writeln!(
            s,
            "| {} | `{}` | {} | {} | {} | {}×{} | {} | {} | {:.1} s |",
            x.job,
            x.scene,
            x.variant.as_deref().unwrap_or("—"),
            x.lights.join("; "),
            x.integrator,
            x.width,
            x.height,
            match x.noise_target {
                Some(t) => format!("≤ {}, to {} % noise", x.samples_per_pixel, t * 100.0),
                None => x.samples_per_pixel.to_string(),
            },
            x.max_depth,
            x.render_s
        );
    }
    let _ = writeln!(s, "\nSeen: {}.\n", r.renders.first().map_or("", |x| x.retinex.as_str()));
}

/// Every file written, linked.
fn images(s: &mut String, r: &Report) {
    let _ = writeln!(s, "## Images\n");
    let _ = writeln!(s, "| file | what |");
    let _ = writeln!(s, "|---|---|");
    for i in &r.images {
        let _ = writeln!(s, "| [`{}`]({}) | {} |", i.file, i.file, i.what);
    }
}

/// The stone experiment's table, after how its colours are measured.
fn stones(s: &mut String, r: &Report) {
    let _ = writeln!(s, "\n## The stones under each light, as rendered and as seen\n");
    let _ = writeln!(
        s,
        "Mean over the inner {:.0} % of each square. *Before*: CIELAB of the render relative to \
         its white tile ({:.0} % reflectance), D65 white — what a camera balanced for daylight \
         shows. *After*: CIELAB of the seen image (adapted to the light; D65 white). ΔE00 to the \
         same square in the D65 render as rendered (before and after) and, after, also as seen \
         (the D65 render's seen image: what an observer sees in daylight; under A people keep \
         some of the light's warmth). *As found* is derived: \
         {:.0} % of the surface covered by a soot proxy.\n",
        INNER_FRACTION * 100.0,
        r.white_reflectance * 100.0,
        r.soot_fraction * 100.0
    );
    let _ = writeln!(
        s,
        "| sample | light | before: L* a* b* | sRGB | before: ΔE00 to D65 rendered | after: L* a* b* \
         | sRGB | after: ΔE00 to D65 rendered | after: ΔE00 to D65 seen |"
    );
    let _ = writeln!(s, "|---|---|---|---|---:|---|---|---:|---:|");
    for c in &r.stones {
        let (b, a) = (&c.before_retinex, &c.after_retinex);
        let _ = writeln!(
            s,
            "| {} | CIE {} | {} | `{}` | {:.2} | {} | `{}` | {:.2} | {:.2} |",
            sample_name(c.stone, c.state),
            c.illuminant,
            lab_text(b.lab),
            b.srgb_hex,
            b.delta_e00_to_d65,
            lab_text(a.lab),
            a.srgb_hex,
            a.delta_e00_to_d65,
            a.delta_e00_to_d65_seen.unwrap_or(f64::NAN)
        );
    }
}

/// What cleaning changes on the facade, light by light.
fn cleaning(s: &mut String, r: &Report) {
    let _ = writeln!(s, "\n## What cleaning changes on the facade\n");
    let _ = writeln!(s, "| light | CIELAB white (cd/m²) | mean ΔE00 | 95th percentile | pixels |");
    let _ = writeln!(s, "|---|---:|---:|---:|---:|");
    for c in &r.cleaning {
        let _ = writeln!(
            s,
            "| {} | {:.0} | {:.2} | {:.2} | {} |",
            c.light.title(),
            c.white_cd_m2,
            c.mean_delta_e00,
            c.p95_delta_e00,
            c.pixels
        );
    }
}

/// The floodlit facade: its grid's illuminance, the map and the files.
fn floodlighting(s: &mut String, r: &Report) {
    let f = &r.floodlighting;
    let _ = writeln!(s, "\n## The facade floodlit at night\n");
    let _ = writeln!(
        s,
        "`{}`: two metal-halide floodlights and an LED spot of measured photometry. The \
         illuminance over the fourth bay (grid `{}`, {} points, {} samples a point, direct and \
         inter-reflected light, computed on the cluster as `restauro illuminance` computes it):\n",
        f.scene, f.grid, f.points, f.samples_per_point
    );
    let _ = writeln!(s, "| minimum | mean | maximum | uniformity E_min/E_mean |");
    let _ = writeln!(s, "|---:|---:|---:|---:|");
    let _ = writeln!(
        s,
        "| {:.1} lx | {:.1} lx | {:.1} lx | {:.3} |\n",
        f.min_lux, f.mean_lux, f.max_lux, f.uniformity
    );
    let _ = writeln!(
        s,
        "![the floodlit bay in false colour]({})\n\nEach point: [`{}`]({}); the document: \
         [`{}`]({}).",
        f.map, f.table, f.table, f.document, f.document
    );
}

/// "travertine (as found)", and the white tile by its name alone (its state is `reference`).
fn sample_name(stone: &str, state: &str) -> String {
    if state == "reference" { stone.to_owned() } else { format!("{stone} ({state})") }
}

/// L* a* b* to one decimal, without the "-0.0" of a value that rounds to zero from below.
fn lab_text(lab: [f64; 3]) -> String {
    let [l, a, b] = lab.map(|v| (v * 10.0).round() / 10.0 + 0.0);
    format!("{l:.1} {a:.1} {b:.1}")
}

#[cfg(test)]
mod tests {
    #[test]
    fn lab_text_shows_no_negative_zero_and_the_white_tile_no_state() {
        assert_eq!(super::lab_text([50.04, -0.04, 12.345]), "50.0 0.0 12.3");
        assert_eq!(super::lab_text([-0.0, -1.24, 0.05]), "0.0 -1.2 0.1");
        assert_eq!(super::sample_name("travertine", "as found"), "travertine (as found)");
        assert_eq!(super::sample_name("white reference", "reference"), "white reference");
    }
}
