//! Every cube of a store decoded for the reference ("everything resident").

use glam::Vec3;

use super::CubeTexels;
use crate::face::FaceLayout;

/// Every cube of a store as the GPU pool holds it, decoded to linear RGB: every mip level
/// and the distance planes ([`FaceLayout`]). The reference's view of "everything resident".
pub struct StoreCubes {
    layout: FaceLayout,
    /// Per cube, per level: six faces of `side(level)²` texels.
    levels: Vec<Vec<Vec<Vec3>>>,
    /// Per cube: six distance planes of `res²` (empty without a distance channel).
    depth: Vec<Vec<f32>>,
    /// Optional residency masks (the GPU cache's indirection table): a face is available
    /// only where its bit is set.
    pub masks: Option<Vec<u32>>,
}

impl StoreCubes {
    /// Decodes every cube of `store` (in parallel) as a renderer on an adapter with BC texture
    /// compression uploads them (BC6H stores as their blocks; the other encodings do not
    /// depend on it). To match a given renderer, use [`StoreCubes::decode_as`] with its
    /// [`crate::Renderer::face_layout`]. Errors name the cube.
    pub fn decode(store: &oslf_format::Store) -> crate::Result<Self> {
        Self::decode_as(store, FaceLayout::for_store(store, true))
    }

    /// Decodes every cube of `store` built as `layout` says (the GPU's payloads: for BC6H the
    /// specification's decoder, what the hardware returns). Errors name the cube.
    pub fn decode_as(store: &oslf_format::Store, layout: FaceLayout) -> crate::Result<Self> {
        use rayon::prelude::*;
        type Cube = (Vec<Vec<Vec3>>, Vec<f32>);
        let cubes = (0..store.cube_count())
            .into_par_iter()
            .map(|cube| -> crate::Result<Cube> {
                let err = |error| crate::RuntimeError::Cube { cube, error };
                let mut levels = vec![Vec::new(); layout.levels as usize];
                let mut depth = Vec::new();
                for face in 0..6u8 {
                    let payload = layout.build(store, cube, face).map_err(err)?;
                    for (l, level) in levels.iter_mut().enumerate() {
                        let rgb = layout.decode_level(&payload, l as u32).map_err(err)?;
                        level.extend(rgb.into_iter().map(Vec3::from_array));
                    }
                    depth.extend(layout.decode_depth(&payload));
                }
                Ok((levels, depth))
            })
            .collect::<crate::Result<Vec<Cube>>>()?;
        let (levels, depth) = cubes.into_iter().unzip();
        Ok(Self {
            layout,
            levels,
            depth,
            masks: None,
        })
    }

    fn available(&self, cube: u32, face: usize) -> bool {
        match &self.masks {
            Some(m) => m.get(cube as usize).copied().unwrap_or(0) & (1 << face) != 0,
            None => true,
        }
    }
}

impl CubeTexels for StoreCubes {
    fn texel(&self, cube: u32, face: usize, level: u32, x: u32, y: u32) -> Option<Vec3> {
        if !self.available(cube, face) {
            return None;
        }
        let n = self.layout.side(level) as usize;
        self.levels
            .get(cube as usize)?
            .get(level as usize)?
            .get(face * n * n + y as usize * n + x as usize)
            .copied()
    }

    fn depth(&self, cube: u32, face: usize, x: u32, y: u32) -> Option<f32> {
        if !self.available(cube, face) {
            return None;
        }
        let n = self.layout.res as usize;
        self.depth
            .get(cube as usize)?
            .get(face * n * n + y as usize * n + x as usize)
            .copied()
    }

    fn resident(&self, cube: u32) -> bool {
        match &self.masks {
            Some(m) => m.get(cube as usize).copied().unwrap_or(0) & 63 != 0,
            None => (cube as usize) < self.levels.len(),
        }
    }
}
