//! Chart packing: flat charts placed in the atlas by their texel masks.
//!
//! A chart at scale `s` occupies a *mask*: its conservative footprint, every texel whose square
//! comes within [`FOOTPRINT_MARGIN`](super::FOOTPRINT_MARGIN) texel of one of its triangles (the chart kept
//! [`CHART_MARGIN`] texel inside its footprint cells). Masks never overlap, so no texel is shared
//! by two charts. Masks may touch: the runtime looks a sample map up at the texel its uv falls
//! in (nearest texel), and a uv of a triangle, even rounded off it by up to the footprint
//! margin, falls in a texel of its own chart's footprint. No gutter texels are needed.
//!
//! Masks are placed one by one, the chart whose mask has the largest smaller side first
//! (ties: more texels, then the lower chart index), each at the lowest, then leftmost, place
//! where it meets no taken texel, over its eight orientations (four quarter turns, of the chart
//! and of its mirror image; bottom-left first fit on a bitmap of the atlas: holes left beside
//! earlier charts are filled). Only places where the mask's first texel falls on a free texel
//! are tested, a 64-texel word at a time. Once all are placed at one scale, [`grow`] enlarges
//! charts one by one into the space left free.

use glam::DVec2;
use rayon::prelude::*;

use super::flatten::Flat;
use super::{touches, CHART_MARGIN};

/// A chart's mask at one scale and orientation.
pub(super) struct Mask {
    /// Width and height in texels.
    pub w: u32,
    pub h: u32,
    /// Per row, bottom to top: the masked texels as bits (bit `x % 64` of word `x / 64`).
    rows: Vec<Vec<u64>>,
    /// The first masked texel of the lowest masked row: `(column, row)`.
    anchor: (u32, u32),
    /// Texels in the mask.
    pub count: u64,
    /// Where the chart's origin lies in the mask, in texels.
    pub origin: DVec2,
    /// Quarter turns (counter-clockwise) of the chart in it, 0 to 3.
    pub turns: u8,
}

/// Where a chart went: the mask's lower-left texel and orientation.
#[derive(Clone, Copy, Debug)]
pub(super) struct Place {
    pub x: u32,
    pub y: u32,
    pub turns: u8,
}

/// A chart in its final place: its mask's lower-left texel, the mask and the chart's scale.
pub(super) struct Placed {
    pub x: u32,
    pub y: u32,
    pub mask: Mask,
    pub scale: DVec2,
}

impl Placed {
    /// A chart point `c` (texels at scale 1) in atlas texels.
    pub fn map(&self, c: DVec2, flat: &Flat) -> DVec2 {
        let q = turn(c * self.scale, flat.size * self.scale, self.mask.turns);
        DVec2::new(f64::from(self.x), f64::from(self.y)) + self.mask.origin + q
    }
}

/// Factors by which [`grow`] tries to enlarge a chart, smallest first.
const GROWTH: [f64; 7] = [1.015, 1.03, 1.07, 1.15, 1.3, 1.6, 2.0];

/// Rounds of [`grow`] over all charts (it stops early when a round grows none).
const GROWTH_ROUNDS: usize = 8;

/// Largest ratio between a chart's two scales (its texels' aspect) that [`grow`] makes.
const MAX_ANISOTROPY: f64 = 2.0;

/// Grows charts one by one, largest first, into the space the packing left free, in rounds
/// until none grows (at most [`GROWTH_ROUNDS`]). Each chart is taken out and put back at the
/// largest scale that fits anywhere (lowest, then leftmost, over its orientations), or where it
/// was: the scale grows by the factors of [`GROWTH`] in turn, in both directions or in one (up
/// to [`MAX_ANISOTROPY`]), each direction until a factor no longer fits; of those that fit, the
/// largest area wins; a chart that found none is not tried again. Charts fill the holes and
/// slivers beside them at a finer texel; no
/// chart gets coarser, and a sample map is read at the nearest texel, so a stretched texel
/// costs nothing but the texels.
pub(super) fn grow(flats: &[Flat], placed: &mut [Placed], a: u32) {
    let mut atlas = Occupancy::new(a);
    for p in placed.iter() {
        atlas.mark(&p.mask, p.x, p.y, true);
    }
    let mut order: Vec<usize> = (0..placed.len()).collect();
    order.sort_by_key(|&i| (std::cmp::Reverse(placed[i].mask.count), i));
    let mut stuck = vec![false; placed.len()];
    for _ in 0..GROWTH_ROUNDS {
        let mut grew = false;
        for &i in &order {
            if stuck[i] {
                continue;
            }
            let p = &mut placed[i];
            atlas.mark(&p.mask, p.x, p.y, false);
            let mut best: Option<Placed> = None;
            for direction in [DVec2::ONE, DVec2::X, DVec2::Y] {
                for factor in GROWTH {
                    let scale = p.scale * (DVec2::ONE + (factor - 1.0) * direction);
                    if scale.max_element() > MAX_ANISOTROPY * scale.min_element() {
                        break;
                    }
                    let mut turned = masks(&flats[i], scale, a);
                    let Some((x, y, o)) = atlas.lowest_fit(&turned) else {
                        break;
                    };
                    if best
                        .as_ref()
                        .is_none_or(|b| scale.x * scale.y > b.scale.x * b.scale.y)
                    {
                        let mask = turned[o].take().expect("the chosen turn has a mask");
                        best = Some(Placed { x, y, mask, scale });
                    }
                }
            }
            match best {
                Some(b) => {
                    *p = b;
                    grew = true;
                }
                None => stuck[i] = true,
            }
            atlas.mark(&p.mask, p.x, p.y, true);
        }
        if !grew {
            break;
        }
    }
}

/// A point `c` of a chart of `size` turned `turns % 4` quarters counter-clockwise, mirrored
/// (`x ↦ size.x − x`) first where `turns ≥ 4`, kept in the first quadrant. A mirrored chart's
/// uvs wind the other way; nothing reads their winding.
fn turn(c: DVec2, size: DVec2, turns: u8) -> DVec2 {
    let c = if turns >= 4 {
        DVec2::new(size.x - c.x, c.y)
    } else {
        c
    };
    match turns % 4 {
        0 => c,
        1 => DVec2::new(size.y - c.y, c.x),
        2 => size - c,
        _ => DVec2::new(c.y, size.x - c.x),
    }
}

/// The mask of `flat` at `scale`, turned `turns` quarters; `None` when it would be wider or
/// taller than `max_side` texels (or not finite).
pub(super) fn mask(flat: &Flat, scale: DVec2, turns: u8, max_side: u32) -> Option<Mask> {
    let size = flat.size * scale;
    let size = if turns % 2 == 1 {
        DVec2::new(size.y, size.x)
    } else {
        size
    };
    let cells = |w: f64| (w + 2.0 * CHART_MARGIN).ceil().max(1.0);
    let (fx, fy) = (cells(size.x), cells(size.y));
    if !(fx <= f64::from(max_side) && fy <= f64::from(max_side)) {
        return None;
    }
    let (w, h) = (fx as u32, fy as u32);
    // Centred in its cells, the chart keeps CHART_MARGIN (more than FOOTPRINT_MARGIN) from
    // their border: its footprint stays inside them.
    let origin = (DVec2::new(fx, fy) - size) / 2.0;
    let (wu, hu) = (w as usize, h as usize);
    let mut rows = vec![vec![0u64; wu.div_ceil(64)]; hu];
    let mut count = 0u64;
    for tri in &flat.corners {
        let p = tri.map(|c| origin + turn(c * scale, flat.size * scale, turns));
        let (lo, hi) = super::bbox(&p);
        let x0 = (lo.x.floor() as i64 - 1).max(0) as usize;
        let y0 = (lo.y.floor() as i64 - 1).max(0) as usize;
        let x1 = (hi.x.floor() as usize + 1).min(wu - 1);
        let y1 = (hi.y.floor() as usize + 1).min(hu - 1);
        for (y, row) in rows.iter_mut().enumerate().take(y1 + 1).skip(y0) {
            for x in x0..=x1 {
                let bit = 1u64 << (x % 64);
                if row[x / 64] & bit == 0 && touches(&p, x as f64, y as f64) {
                    row[x / 64] |= bit;
                    count += 1;
                }
            }
        }
    }
    let anchor = rows
        .iter()
        .enumerate()
        .find_map(|(y, row)| {
            row.iter()
                .enumerate()
                .find(|(_, &word)| word != 0)
                .map(|(j, word)| (j as u32 * 64 + word.trailing_zeros(), y as u32))
        })
        .unwrap_or((0, 0));
    Some(Mask {
        w,
        h,
        rows,
        anchor,
        count,
        origin,
        turns,
    })
}

/// Places `masks` (per chart, one per quarter turn, `None` where too large) into an `a × a`
/// atlas; `None` if they do not fit.
pub(super) fn pack(masks: &[[Option<Mask>; TURNS]], a: u32) -> Option<Vec<Place>> {
    let mut order: Vec<usize> = (0..masks.len()).collect();
    let height = |i: usize| {
        masks[i]
            .iter()
            .flatten()
            .map(|m| (m.h.min(m.w), m.count))
            .max()
            .unwrap_or((0, 0))
    };
    order.sort_by(|&i, &j| height(j).cmp(&height(i)).then(i.cmp(&j)));
    let mut atlas = Occupancy::new(a);
    let mut places = vec![
        Place {
            x: 0,
            y: 0,
            turns: 0
        };
        masks.len()
    ];
    for i in order {
        let (x, y, o) = atlas.lowest_fit(&masks[i])?;
        let m = masks[i][o].as_ref().expect("the chosen turn has a mask");
        atlas.mark(m, x, y, true);
        places[i] = Place {
            x,
            y,
            turns: m.turns,
        };
    }
    Some(places)
}

/// The atlas's taken texels, one bit each, row by row.
struct Occupancy {
    a: u32,
    words: usize,
    rows: Vec<Vec<u64>>,
}

impl Occupancy {
    fn new(a: u32) -> Self {
        let words = (a as usize).div_ceil(64) + 1;
        Self {
            a,
            words,
            rows: vec![vec![0; words]; a as usize],
        }
    }

    /// Whether `m` at `(x, y)` meets a taken texel.
    fn collides(&self, m: &Mask, x: u32, y: u32) -> bool {
        let (w0, s) = ((x / 64) as usize, x % 64);
        m.rows.iter().enumerate().any(|(r, bits)| {
            let row = &self.rows[y as usize + r];
            bits.iter().enumerate().any(|(j, &b)| {
                b != 0
                    && (row[w0 + j] & (b << s) != 0
                        || (s > 0 && row[w0 + j + 1] & (b >> (64 - s)) != 0))
            })
        })
    }

    /// The lowest, then leftmost, free place over the turns of a chart (`None` where a turn is
    /// too large): `(x, y, turn)`.
    fn lowest_fit(&self, turned: &[Option<Mask>; TURNS]) -> Option<(u32, u32, usize)> {
        let mut best: Option<(u32, u32, usize)> = None;
        for (o, m) in turned.iter().enumerate() {
            let Some(m) = m else { continue };
            if let Some((x, y)) = self.first_fit(m, best.map(|b| b.1)) {
                if best.is_none_or(|(bx, by, _)| (y, x) < (by, bx)) {
                    best = Some((x, y, o));
                }
            }
        }
        best
    }

    /// The lowest, then leftmost, free place for `m` at or below row `below` (all rows when
    /// `None`): only columns where the mask's anchor texel falls on a free texel are tried.
    fn first_fit(&self, m: &Mask, below: Option<u32>) -> Option<(u32, u32)> {
        if m.w > self.a || m.h > self.a {
            return None;
        }
        let (ax, ay) = m.anchor;
        let last_y = (self.a - m.h).min(below.unwrap_or(u32::MAX));
        for y in 0..=last_y {
            let row = &self.rows[(y + ay) as usize];
            for (j, &word) in row.iter().enumerate().take(self.words - 1) {
                let mut free = !word;
                while free != 0 {
                    let bit = free.trailing_zeros();
                    free &= free - 1;
                    let column = j as u32 * 64 + bit;
                    if column < ax || column - ax > self.a - m.w {
                        continue;
                    }
                    let x = column - ax;
                    if !self.collides(m, x, y) {
                        return Some((x, y));
                    }
                }
            }
        }
        None
    }

    /// Takes (`taken`) or frees the texels of `m` at `(x, y)`.
    fn mark(&mut self, m: &Mask, x: u32, y: u32, taken: bool) {
        let (w0, s) = ((x / 64) as usize, x % 64);
        let set = |word: &mut u64, bits: u64| {
            if taken {
                *word |= bits;
            } else {
                *word &= !bits;
            }
        };
        for (r, bits) in m.rows.iter().enumerate() {
            let row = &mut self.rows[y as usize + r];
            for (j, &b) in bits.iter().enumerate() {
                set(&mut row[w0 + j], b << s);
                if s > 0 {
                    set(&mut row[w0 + j + 1], b >> (64 - s));
                }
            }
        }
    }
}

/// Orientations tried per chart: quarter turns 0 to 3.
pub(super) const TURNS: usize = 8;

/// The masks of `flat` at `scale` in each orientation (quarter turns 0 to 3, then the same of
/// the mirrored chart), built in parallel; `None` where too large for `max_side`.
pub(super) fn masks(flat: &Flat, scale: DVec2, max_side: u32) -> [Option<Mask>; TURNS] {
    let mut out: [Option<Mask>; TURNS] = Default::default();
    out.par_iter_mut()
        .enumerate()
        .for_each(|(t, m)| *m = mask(flat, scale, t as u8, max_side));
    out
}
