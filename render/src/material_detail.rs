//! The detail each material of a prepared scene takes over its measured reflectance: from a
//! photo (the scene's `texture` for its state, or the part's own from its mesh file; balanced
//! on its grey patch when the material gives one), or from the part's vertex colours; and the
//! mean it is relative to, over the surfaces the material covers, weighted by area.
//!
//! A photo's mean samples each triangle at 16 points spread over it, on the level where it
//! spans about 4 × 4 texels; vertex colours vary linearly over a triangle, so the mean of its
//! three corners is its mean exactly.

use crate::texture::{Detail, Pyramid, TexturedTriangle, inverse_smooth_spectrum, luminance};
use crate::vertex_colour::{PaletteBuilder, VertexPalette};
use glam::{Vec2, Vec3A};
use restauro_scene::load::LoadedScene;
use restauro_scene::mesh::Mesh;
use restauro_scene::scene_file::Detail as DetailKind;
use restauro_scene::texture::Texture;
use std::collections::BTreeMap;
use std::sync::Arc;

/// What a part brings of its own from its mesh file.
pub(crate) enum Own {
    Photo(Arc<Texture>),
    VertexColours,
}

/// A part's own detail (its file's photo, else its vertex colours when `coloured`), by a key
/// naming the part, when it shows ([`restauro_scene::scene_file::Material::shows_file_detail`]).
pub(crate) fn own_detail(
    scene: &LoadedScene,
    (material, state): (&str, &str),
    object: &str,
    group: &restauro_scene::mesh::Group,
    coloured: bool,
) -> Option<(String, Own)> {
    if !scene.file.materials[material].shows_file_detail(state) {
        return None;
    }
    if let Some(photo) = &group.photo {
        return Some((format!("{object}#{}", group.name), Own::Photo(photo.clone())));
    }
    coloured.then(|| (format!("{object}#{} vertex colours", group.name), Own::VertexColours))
}

/// What gives a material its detail.
enum Source {
    Photo(Pyramid),
    Vertices(DetailKind),
}

/// A material's source, and Σ area·colour and Σ area over the surfaces seen so far.
struct Gathering {
    source: Source,
    sum: [f64; 3],
    area_m2: f64,
}

/// A triangle's share in its material's detail.
pub(crate) enum Surface {
    Textured(TexturedTriangle),
    /// Its corners' colours, as indices in the palette.
    Coloured([u32; 3]),
}

/// The details of the materials being prepared.
#[derive(Default)]
pub(crate) struct MaterialDetails {
    /// A pyramid per photo and kind of detail, however many materials share it.
    pyramids: BTreeMap<(String, DetailKind), Pyramid>,
    /// Per material (in the order of the prepared scene's materials).
    of_material: Vec<Option<Gathering>>,
    palette: PaletteBuilder,
}

impl MaterialDetails {
    /// The next material: `own` is what its part brings, by a key, when it shows.
    pub(crate) fn add_material(
        &mut self,
        scene: &LoadedScene,
        name: &str,
        state: &str,
        own: Option<(String, Own)>,
    ) {
        let m = &scene.file.materials[name];
        let kind = m.detail.unwrap_or_default();
        let photo = match m.texture_of(state) {
            Some(reference) => {
                scene.textures.get(reference).map(|t| (reference.to_owned(), t.clone()))
            }
            None => match own {
                Some((key, Own::Photo(texture))) => Some((key, texture)),
                Some((_, Own::VertexColours)) => {
                    self.of_material.push(Some(Gathering::new(Source::Vertices(kind))));
                    return;
                }
                None => None,
            },
        };
        // A photo balanced on a grey patch is another photo, keyed by its patch too.
        let patch = m.white_patch_of(state);
        let source = photo.and_then(|(key, texture)| {
            let key = match patch {
                Some(p) => format!("{key} balanced on {},{} {}×{}", p.x, p.y, p.width, p.height),
                None => key,
            };
            let pyramid = match self.pyramids.entry((key, kind)) {
                std::collections::btree_map::Entry::Occupied(e) => e.get().clone(),
                std::collections::btree_map::Entry::Vacant(e) => {
                    let pyramid = match patch {
                        Some(p) => Pyramid::new(&texture.white_balanced(p), kind),
                        None => Pyramid::new(&texture, kind),
                    };
                    e.insert(pyramid?).clone()
                }
            };
            Some(Source::Photo(pyramid))
        });
        self.of_material.push(source.map(Gathering::new));
    }

    /// Each vertex's colour as an index in the palette ([`u32::MAX`] for none), when one of
    /// `materials` (a mesh's, by part) takes its detail from them.
    pub(crate) fn vertex_colours(&mut self, mesh: &Mesh, materials: &[u32]) -> Option<Vec<u32>> {
        let colours = mesh.colours.as_ref()?;
        let wanted = materials.iter().any(|&m| {
            let source = self.of_material[m as usize].as_ref().map(|g| &g.source);
            matches!(source, Some(Source::Vertices(_)))
        });
        wanted.then(|| {
            let index =
                |c: &[f32; 3]| if c[0].is_nan() { u32::MAX } else { self.palette.index(*c) };
            colours.iter().map(index).collect()
        })
    }

    /// Triangle `t` of a mesh, of material `bsdf`, as its material's detail needs it: textured
    /// when the material has a photo (the loader made sure its vertices have texture
    /// coordinates), coloured when it takes vertex colours (`colours`, from
    /// [`MaterialDetails::vertex_colours`]).
    pub(crate) fn triangle(
        &mut self,
        bsdf: u32,
        mesh: &Mesh,
        t: &[u32; 3],
        [a, b, c]: [Vec3A; 3],
        colours: Option<&[u32]>,
    ) -> Option<Surface> {
        let gathering = self.of_material.get_mut(bsdf as usize)?.as_mut()?;
        let area_m2 = 0.5 * (b - a).cross(c - a).length();
        let surface = match &gathering.source {
            Source::Photo(pyramid) => {
                let texcoords = mesh.texcoords.as_ref()?;
                let uv = t.map(|i| Vec2::from(texcoords[i as usize]));
                let triangle = TexturedTriangle::new(uv, area_m2, pyramid.size());
                let lod = (triangle.whole_level(pyramid.size()) - 2.0).max(0.0);
                let points = TexturedTriangle::spread_points();
                let weight = f64::from(area_m2) / points.len() as f64;
                for w in points {
                    add(&mut gathering.sum, pyramid.colour(triangle.at(w).uv, lod), weight);
                }
                Surface::Textured(triangle)
            }
            Source::Vertices(_) => {
                let corners = t.map(|i| colours.map_or(u32::MAX, |c| c[i as usize]));
                if corners.contains(&u32::MAX) {
                    return None;
                }
                let weight = f64::from(area_m2) / 3.0;
                for c in corners {
                    add(&mut gathering.sum, self.palette.colour(c), weight);
                }
                Surface::Coloured(corners)
            }
        };
        gathering.area_m2 += f64::from(area_m2);
        Some(surface)
    }

    /// Each material's detail, the pyramids to account for, and the vertices' palette (when a
    /// material takes vertex colours).
    pub(crate) fn details(self) -> (Vec<Option<Detail>>, Vec<Pyramid>, Option<Arc<VertexPalette>>) {
        let chromatic = self
            .of_material
            .iter()
            .flatten()
            .any(|g| matches!(g.source, Source::Vertices(DetailKind::Chromatic)));
        let vertices = self
            .of_material
            .iter()
            .flatten()
            .any(|g| matches!(g.source, Source::Vertices(_)) && g.area_m2 > 0.0);
        let palette = vertices.then(|| Arc::new(self.palette.finish(chromatic)));
        let details = self
            .of_material
            .into_iter()
            .map(|gathering| {
                let g = gathering?;
                // A photo on no surface has no mean, and no detail to give.
                (g.area_m2 > 0.0).then_some(())?;
                let mean = g.sum.map(|c| (c / g.area_m2) as f32);
                match g.source {
                    Source::Photo(pyramid) => pyramid.detail(mean),
                    Source::Vertices(kind) => vertex_detail(palette.clone()?, kind, mean),
                }
            })
            .collect();
        (details, self.pyramids.into_values().collect(), palette)
    }
}

impl Gathering {
    fn new(source: Source) -> Self {
        Self { source, sum: [0.0; 3], area_m2: 0.0 }
    }
}

/// Σ area·colour ← Σ area·colour + `weight`·`colour`.
fn add(sum: &mut [f64; 3], colour: [f32; 3], weight: f64) {
    (0..3).for_each(|k| sum[k] += f64::from(colour[k]) * weight);
}

/// The detail vertex colours of linear mean `mean` give; `None` for a black mean, which has
/// no detail to give.
fn vertex_detail(palette: Arc<VertexPalette>, kind: DetailKind, mean: [f32; 3]) -> Option<Detail> {
    match kind {
        DetailKind::Chromatic => {
            let inverse_mean = inverse_smooth_spectrum(mean)?;
            Some(Detail::VertexChromatic { palette, inverse_mean })
        }
        _ => {
            let y = luminance(mean);
            (y > 0.0).then(|| Detail::VertexLuminance { palette, inverse_mean: 1.0 / y })
        }
    }
}
