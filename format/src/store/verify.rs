//! Full verification of an open store ([`Store::verify`]): what opening does not check, byte
//! by byte.

use super::*;

/// Counters from [`Store::verify`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct VerifyReport {
    /// Cubes checked.
    pub cubes: u32,
    /// Faces whose checksum matched and which decompressed to their raw size.
    pub faces: u64,
    /// Compressed bytes checked.
    pub compressed_bytes: u64,
    /// Raw bytes decompressed.
    pub raw_bytes: u64,
    /// Padding bytes checked to be zero (between sections and after each cube record).
    pub padding_bytes: u64,
}

impl Store {
    /// Checks what [`Store::open`] does not, byte by byte: every padding region is zero (after
    /// the metadata, sample points and sample maps, and after each cube record's frames;
    /// [`Error::NonZeroPadding`] names the byte offset), every cube record header agrees with
    /// the table of contents, every frame matches its checksum and decompresses to exactly
    /// its filtered size, and the decoded faces match the
    /// header's checksum of them ([`Error::DecodedChecksum`]), which catches a changed face
    /// filter id or `mantissa_bits`.
    pub fn verify(&self) -> Result<VerifyReport, Error> {
        let mut report = VerifyReport::default();
        let h = &self.header;
        for (region, s) in [
            ("after the metadata section", h.meta),
            ("after the sample points section", h.points),
            ("after the sample maps section", h.maps),
        ] {
            report.padding_bytes += self.check_padding(s.end(), region)?;
        }
        let mut decoded = Xxh3::new();
        let mut buf = vec![0u8; self.face_raw_size];
        let res = h.cube_resolution;
        let color_bytes = h
            .encoding
            .face_bytes(res)
            .unwrap_or(usize::MAX)
            .min(buf.len());
        let mut texels = vec![[0.0f32; 3]; (res as usize) * (res as usize)];
        // The first cube whose irradiance record is not its faces' projection: reported after
        // the decoded-faces checksum, which names the likelier cause of changed texels.
        let mut irradiance_mismatch = None;
        for cube in 0..self.cube_count() {
            let mut projection = Projection::new(res);
            let first = self.face_entry(cube, 0)?;
            let rec_off = first.offset.saturating_sub(RECORD_HEADER_BYTES as u64);
            let rec_bytes = self.backing.read(Section {
                offset: rec_off,
                size: RECORD_HEADER_BYTES as u64,
            })?;
            let rec_bytes = &rec_bytes[..];
            let bad = |detail: String| Error::InvalidCubeRecord {
                cube,
                offset: rec_off,
                detail,
            };
            let rec = RecordHeader::parse(rec_bytes).map_err(bad)?;
            if rec.cube != cube {
                return Err(bad(format!("record says cube {}", rec.cube)));
            }
            for face in 0..FACES {
                let e = self.face_entry(cube, face)?;
                if rec.faces[face] != (e.compressed_size, e.raw_size, e.checksum) {
                    return Err(bad(format!(
                        "face {face}: record {:?} disagrees with the table of contents {e:?}",
                        rec.faces[face]
                    )));
                }
                self.read_face_raw(cube, face, &mut buf)?;
                decoded.update(&xxh3_64(&buf).to_le_bytes());
                if self.irradiance.is_some() {
                    decode_face_texels(
                        h.encoding,
                        res,
                        &buf[..color_bytes],
                        &mut texels,
                        cube,
                        face,
                    )?;
                    projection.face(face, &texels);
                }
                report.faces += 1;
                report.compressed_bytes += e.compressed_size;
                report.raw_bytes += e.raw_size;
            }
            let last = self.face_entry(cube, FACES - 1)?;
            let end = last.offset.saturating_add(last.compressed_size);
            report.padding_bytes +=
                self.check_padding(end, &format!("after the frames of cube {cube}"))?;
            if let Some(stored) = &self.irradiance {
                let same = projection.finish(cube).ok() == Some(stored[cube as usize]);
                if !same && irradiance_mismatch.is_none() {
                    irradiance_mismatch = Some(Error::IrradianceMismatch {
                        cube,
                        offset: h.irradiance.offset
                            + u64::from(cube) * IRRADIANCE_CUBE_BYTES as u64,
                    });
                }
            }
            report.cubes += 1;
        }
        if h.has_irradiance() {
            report.padding_bytes +=
                self.check_padding(h.irradiance.end(), "after the irradiance section")?;
        }
        let computed = decoded.digest();
        if computed != h.decoded_checksum {
            return Err(Error::DecodedChecksum {
                stored: h.decoded_checksum,
                computed,
            });
        }
        if let Some(e) = irradiance_mismatch {
            return Err(e);
        }
        Ok(report)
    }

    /// Checks that the padding from `end` to the next multiple of 8 is zero; returns its length.
    fn check_padding(&self, end: u64, region: &str) -> Result<u64, Error> {
        let pad = Section {
            offset: end,
            size: align8(end).unwrap_or(end) - end,
        };
        let bytes = self.backing.read(pad)?;
        match bytes.iter().position(|v| *v != 0) {
            Some(i) => Err(Error::NonZeroPadding {
                region: region.to_string(),
                offset: end + i as u64,
                value: bytes.get(i).copied().unwrap_or(0),
            }),
            None => Ok(pad.size),
        }
    }
}
