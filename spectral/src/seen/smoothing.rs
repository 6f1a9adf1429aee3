//! Smoothing within frameworks of illumination: a normalised convolution, Σ v·m / Σ m with m a
//! framework's area, so that what is smoothed on one side of a shadow's edge takes nothing from
//! the other. The seen image smooths the light (`white`) and the paths' change to lightness
//! (`super`) so.
//!
//! It runs on a grid of cells (a 256th of the diagonal, 8 px at 1920 × 1080): the quantities
//! smoothed are smooth at that scale. Three box passes approximate a Gaussian, and a pixel
//! reads its framework's cells bilinearly.

use crate::retinex::Frameworks;
use rayon::prelude::*;

/// Cells per image diagonal.
const CELLS_PER_DIAGONAL: f64 = 256.0;
/// The weight below which a framework's smoothing is taken not to reach a pixel: a few of its
/// pixels' worth.
const LEAST_WEIGHT: f64 = 1e-3;

/// The running sums of one framework on the grid of cells: Σ v·m (four values) and Σ m.
type Cells = Vec<[f64; 5]>;

/// The grid of cells an image is smoothed on.
#[derive(Clone, Copy)]
struct Grid {
    cell_px: usize,
    columns: usize,
    rows: usize,
}

impl Grid {
    fn of(width: usize, height: usize) -> Self {
        let diagonal = ((width * width + height * height) as f64).sqrt();
        let cell_px = ((diagonal / CELLS_PER_DIAGONAL).round() as usize).max(1);
        Grid { cell_px, columns: width.div_ceil(cell_px), rows: height.div_ceil(cell_px) }
    }

    /// The half-width (in cells) of each of three box passes whose sum is a Gaussian of σ
    /// (pixels): a box of width b has variance (b² − 1)/12, three of them 3(b² − 1)/12.
    fn box_radius(&self, sigma_px: f64) -> usize {
        let sigma_cells = sigma_px / self.cell_px as f64;
        let width = (4.0 * sigma_cells * sigma_cells + 1.0).sqrt();
        ((width - 1.0) / 2.0).round().max(0.0) as usize
    }
}

/// One pass of a box filter of half-width `r` along rows (`along_rows`) or columns, on the
/// grid, clipped at its edges (the sums of a normalised convolution need no weights).
fn box_pass(cells: &Cells, grid: Grid, r: usize, along_rows: bool) -> Cells {
    let (lines, length) =
        if along_rows { (grid.rows, grid.columns) } else { (grid.columns, grid.rows) };
    let index = |line: usize, i: usize| {
        if along_rows { line * grid.columns + i } else { i * grid.columns + line }
    };
    let mut out = vec![[0.0; 5]; cells.len()];
    let lines_out: Vec<Vec<[f64; 5]>> = (0..lines)
        .into_par_iter()
        .map(|line| {
            // A prefix sum along the line, then each window's difference.
            let mut prefix = vec![[0.0f64; 5]; length + 1];
            for i in 0..length {
                let v = cells[index(line, i)];
                prefix[i + 1] = std::array::from_fn(|c| prefix[i][c] + v[c]);
            }
            (0..length)
                .map(|i| {
                    let (a, b) = (i.saturating_sub(r), (i + r + 1).min(length));
                    std::array::from_fn(|c| prefix[b][c] - prefix[a][c])
                })
                .collect()
        })
        .collect();
    for (line, values) in lines_out.into_iter().enumerate() {
        for (i, v) in values.into_iter().enumerate() {
            out[index(line, i)] = v;
        }
    }
    out
}

/// Bilinear read of the cells at pixel (x, y), the cells' values standing at their centres.
fn read(cells: &Cells, grid: Grid, x: usize, y: usize) -> [f64; 5] {
    let at = |v: usize, n: usize| {
        let c = (v as f64 + 0.5) / grid.cell_px as f64 - 0.5;
        let c = c.clamp(0.0, (n - 1) as f64);
        let i = (c.floor() as usize).min(n.saturating_sub(2));
        (i, (c - i as f64).clamp(0.0, 1.0))
    };
    let (i, tx) = at(x, grid.columns);
    let (j, ty) = at(y, grid.rows);
    let (i1, j1) = ((i + 1).min(grid.columns - 1), (j + 1).min(grid.rows - 1));
    let c = |ii: usize, jj: usize| cells[jj * grid.columns + ii];
    let (a, b, d, e) = (c(i, j), c(i1, j), c(i, j1), c(i1, j1));
    std::array::from_fn(|k| {
        (a[k] * (1.0 - tx) + b[k] * tx) * (1.0 - ty) + (d[k] * (1.0 - tx) + e[k] * tx) * ty
    })
}

/// A smoother for one image's frameworks.
pub(super) struct Smoother<'a> {
    grid: Grid,
    radius: usize,
    frameworks: &'a Frameworks,
    width: usize,
}

/// Per framework, the smoothed sums of what [`Smoother::smooth`] was given.
pub(super) struct Smoothed(Vec<Cells>);

impl<'a> Smoother<'a> {
    /// A Gaussian of σ = `sigma_of_diagonal` of the image diagonal.
    pub(super) fn new(
        frameworks: &'a Frameworks,
        (width, height): (usize, usize),
        sigma_of_diagonal: f64,
    ) -> Self {
        let grid = Grid::of(width, height);
        let diagonal = ((width * width + height * height) as f64).sqrt();
        Smoother { grid, radius: grid.box_radius(sigma_of_diagonal * diagonal), frameworks, width }
    }

    /// Smooths `value` (four numbers a pixel) over each framework's area, at the pixels where
    /// it is `Some`.
    pub(super) fn smooth(&self, value: impl Fn(usize) -> Option<[f64; 4]> + Sync) -> Smoothed {
        let (grid, f) = (self.grid, self.frameworks);
        let height = f.labels.len() / self.width;
        // Each row of cells sums its own band of pixel rows, in parallel: a cell takes its
        // pixels in the same order as a pass over the whole image would, so the sums are the
        // same to the bit.
        let bands: Vec<Vec<Cells>> = (0..grid.rows)
            .into_par_iter()
            .map(|row| {
                let mut band: Vec<Cells> = vec![vec![[0.0; 5]; grid.columns]; f.count];
                let rows = row * grid.cell_px..((row + 1) * grid.cell_px).min(height);
                for p in rows.flat_map(|y| y * self.width..(y + 1) * self.width) {
                    let Some(v) = f.solid[p].then(|| value(p)).flatten() else { continue };
                    let cell = &mut band[usize::from(f.labels[p])][(p % self.width) / grid.cell_px];
                    for c in 0..4 {
                        cell[c] += v[c];
                    }
                    cell[4] += 1.0;
                }
                band
            })
            .collect();
        let mut cells: Vec<Cells> = vec![Vec::with_capacity(grid.columns * grid.rows); f.count];
        for band in bands {
            for (framework, row) in cells.iter_mut().zip(band) {
                framework.extend(row);
            }
        }
        Smoothed(
            cells
                .into_iter()
                .map(|mut c| {
                    for along_rows in [true, false] {
                        for _ in 0..3 {
                            c = box_pass(&c, grid, self.radius, along_rows);
                        }
                    }
                    c
                })
                .collect(),
        )
    }

    /// The framework pixel `p` is seen in: its own, or for a pixel outside every framework's
    /// area, the one whose smoothing weighs most there.
    pub(super) fn framework_of(&self, s: &Smoothed, p: usize) -> usize {
        let f = self.frameworks;
        if f.solid[p] || f.count == 1 {
            return usize::from(f.labels[p]);
        }
        let (x, y) = (p % self.width, p / self.width);
        (0..f.count)
            .max_by(|&a, &b| {
                read(&s.0[a], self.grid, x, y)[4].total_cmp(&read(&s.0[b], self.grid, x, y)[4])
            })
            .expect("at least one framework")
    }

    /// The smoothed mean of framework `f` at pixel `p`; `None` where it does not reach.
    pub(super) fn at(&self, s: &Smoothed, f: usize, p: usize) -> Option<[f64; 4]> {
        let v = read(&s.0[f], self.grid, p % self.width, p / self.width);
        (v[4] > LEAST_WEIGHT).then(|| std::array::from_fn(|c| v[c] / v[4]))
    }
}
