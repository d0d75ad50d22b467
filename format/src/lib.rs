//! # The OSLF store
//!
//! An OSLF store holds an *offset surface light field* (Jason Ang, 2003): HDR cube maps captured
//! at sample points offset by ε above the surfaces of its objects (bicubic Bézier patches or,
//! from version 5, triangle meshes), plus *sample maps* giving, for each texel of a map's
//! (u, v) domain, the 4 nearest sample points. A Bézier patch has one sample map; a triangle
//! mesh has an atlas of `k × k` sample maps ("pages", see "Triangle-mesh objects"). Where the
//! layout says *patch* index or count, read *map*: a Bézier patch or an atlas page. The
//! bake writes it with [`StoreWriter`]; the runtime reads it with [`Store`], which reads the
//! fixed sections and the table of contents into memory, validates every structural byte before
//! trusting it, and reads cube frames with positioned reads as they are needed (no memory map:
//! a file overwritten while open gives an error naming the offset, never a SIGBUS).
//!
//! This documentation is the format specification: it is complete enough to write a reader in
//! another language.
//!
//! ## Conventions
//!
//! * All integers are little-endian; all floats are IEEE-754 little-endian. `u64` for every
//!   offset and size (stores larger than 4 GiB work).
//! * Every offset is absolute (from the start of the file). Every section starts at a multiple
//!   of 8; the bytes between the end of a section and the next multiple of 8 are zero padding.
//! * Checksums are **xxh3-64 with seed 0** (`XXH3_64bits`) of the bytes named.
//! * Sections appear in this order, each starting at the 8-aligned end of the previous one,
//!   with no other gaps:
//!   `header (256 B) | metadata | sample points | sample maps | cube payload | table of contents`.
//!   The table of contents ends the file.
//!
//! ## Header (256 bytes at offset 0)
//!
//! | offset | type      | field |
//! |-------:|-----------|-------|
//! | 0      | `[u8; 8]` | magic [`MAGIC`] = `"OSLFSTOR"` |
//! | 8      | `u32`     | version = [`VERSION`] (8); readers also accept [`MIN_VERSION`] (1) to 7, see "Versions" |
//! | 12     | `u32`     | flags: bit 0 distance channel, bit 1 environment cube, bit 2 COMPLETE (set by `finish()`); other bits must be 0 |
//! | 16     | `u32`     | encoding: 0 RGB9E5, 1 RGBA16F, 2 RGBA32F, 3 BC6H (version 4 and later: in an older store 3 is [`Error::EncodingVersion`]) |
//! | 20     | `u32`     | sample-map index bytes: 2 if sample_count ≤ 65535, else 4 |
//! | 24     | `u32`     | cube face resolution `n` (1..=16384) |
//! | 28     | `u32`     | sample-map resolution `m` per patch (1..=16384) |
//! | 32     | `u64`     | sample_count (sample points) |
//! | 40     | `u64`     | cube_count = sample_count + (1 if environment cube) (≤ 2³²−1) |
//! | 48     | `u64`     | patch_count: the number of sample maps (Bézier patches plus atlas pages; before version 5, patches) |
//! | 56     | `u64`     | object_count |
//! | 64     | `u64` ×2  | metadata offset (= 256), size |
//! | 80     | `u64` ×2  | sample points offset, size (= 40 × sample_count) |
//! | 96     | `u64` ×2  | sample maps offset, size (= patch_count × m² × 4 × index bytes) |
//! | 112    | `u64` ×2  | cube payload offset, size |
//! | 128    | `u64` ×2  | table of contents offset, size (= 192 × cube_count + 8) |
//! | 144    | `u64`     | file size in bytes |
//! | 152    | `u64`     | checksum of the metadata section |
//! | 160    | `u64`     | checksum of the sample points section |
//! | 168    | `u64`     | checksum of the sample maps section |
//! | 176    | `u32`     | face filter: 0 none, 1 predict, 2 predict-rows, 3 predict-packed (see "Face filters"; writers use 3 for RGB9E5 with `mantissa_bits` ≤ 6, else 2); other ids are refused ([`Error::UnknownFilter`]) |
//! | 180    | `u64`     | checksum of the decoded faces (version 3 and later; see "Checksum of the decoded faces"): written by `finish()`, zero in a partial file. Versions 1 and 2: reserved, zero |
//! | 188    | 60 bytes  | reserved, zero |
//! | 248    | `u64`     | checksum of header bytes 0..248 |
//!
//! A reader checks, in order: magic, version, header checksum, flags, tags, filter, reserved bytes
//! (180..248 in versions 1 and 2, 188..248 from version 3), that the encoding is allowed in the
//! version;
//! refuses files without the COMPLETE flag ([`Error::NotFinished`]); then the section layout
//! against the real file size; then each section's checksum before parsing it. The header's
//! encoding, resolutions, flags and counts must agree with the metadata.
//!
//! ## Metadata section
//!
//! | bytes | content |
//! |------:|---------|
//! | 4, 4  | `u32` object_count, `u32` patch_count = map count (equal to the header's) |
//! | 80    | bake parameters: `f32` epsilon (> 0), `f32` phi_samplemap_deg (0..=180), `u32` cube_resolution, `u32` sample_map_resolution, `u32` samples_per_texel, `u32` bounces, `u64` seed, `u32` encoding tag (as the header's; 3 only from version 4), `u32` distance_channel (0/1), `i32` zstd_level (zstd's valid range), `u32` has_env_cube (0/1), `[u8; 32]` scene_hash |
//! | 4     | `u32` mantissa_bits: RGB9E5 mantissa bits kept per channel, 1..=9, and exactly 9 unless the encoding is RGB9E5 (see "Quantized RGB9E5"). Versions 2 and 3: absent in version 1, whose stores read as 9 |
//! | 44    | camera: `u32` present (0/1), `f32`×3 position, `f32`×3 target, `f32`×3 up, `f32` vfov_deg (in (0, 180) when present; all 44 bytes are zero when absent) |
//! | …     | object_count objects, each: `u32` name length L (≤ [`MAX_NAME_BYTES`] = 4096), L bytes UTF-8 name (no padding), `f32`×16 column-major object→world transform, `f32`×3 base colour, `u32` first_patch, `u32` patch_count (its maps `first_patch..first_patch + patch_count`); from version 5, then `u32` kind (0 Bézier patches, 1 triangle mesh) and, for kind 1, the mesh record below; from version 7, then the material record below; from version 8, then the texture record below |
//! | 192 × B | the Bézier patches' control points, B = Σ patch_count over the Bézier objects (before version 5 every object is Bézier, so B = patch_count), in object order, each 16 control points × `f32`×3 (object space); `CP_ij` at index `4i + j`, `i` along u, `j` along v |
//!
//! A **material record** (version 7 and later) ends each object record (after its mesh record,
//! if any), 24 bytes:
//!
//! | bytes | content |
//! |------:|---------|
//! | 4     | `u32` model: 0 Lambertian (the base colour alone), 1 glTF metallic-roughness (the base colour with the two factors, glTF 2.0 Appendix B) |
//! | 4, 4  | `f32` metallic, `f32` roughness: each in `[0, 1]` for model 1, both 0 for model 0 |
//! | 12    | `f32`×3 emission: emitted radiance, linear RGB, finite and ≥ 0 |
//!
//! A **texture record** (version 8 and later) ends each object record (after its material
//! record). Only a mesh object may hold textures; its images are read at texture coordinates
//! interpolated over its triangles like the normals (see "Object textures"):
//!
//! | bytes | content |
//! |------:|---------|
//! | 4     | `u32` flags: bit 0 base colour, 1 metallic-roughness, 2 normal, 3 occlusion, 4 emissive ([`TextureKind`]); other bits 0. When 0 the record ends here |
//! | 4, 4  | `f32` normal_scale (finite), `f32` occlusion_strength in `[0, 1]` |
//! | 8 × V | texture coordinates, `f32`×2 per mesh vertex, finite |
//! | 16 × V | only with a normal texture: tangents, `f32`×3 unit (object space, length 1 within 1e-3) and `f32` w = ±1 (the bitangent is `w·(n × t)`), per mesh vertex |
//! | …     | one image per flag bit, in bit order: `u32` width, `u32` height (each 1..=[`textures::MAX_TEXTURE_SIDE`], at most [`textures::MAX_TEXTURE_TEXELS`] texels), `u32` frame length L, L bytes: one zstd frame that decompresses to exactly width × height × 4 bytes, RGBA8 texels row-major, row 0 at the top |
//!
//! A **mesh record** (object kind 1, version 5 and later) continues the object record:
//!
//! | bytes | content |
//! |------:|---------|
//! | 4     | `u32` atlas grid `k` ≥ 1, with `k²` = the object's patch_count |
//! | 4, 4  | `u32` vertex_count V ≥ 3, `u32` triangle_count T ≥ 1 |
//! | 32 × V | vertices: `f32`×3 position (object space), `f32`×3 unit normal (object space; length 1 within 1e-3), `f32`×2 atlas uv in `[0, 1]²` |
//! | 12 × T | triangles: `u32`×3 vertex indices, each `< V` |
//!
//! The section must end exactly after the last Bézier patch. Every float is finite. The
//! objects' map ranges tile `0..patch_count`: the first starts at 0, each starts where the
//! previous one ends, the last ends at patch_count (empty ranges are allowed for Bézier
//! objects). Readers check a mesh's counts against the bytes left in the section before
//! allocating anything. The Bézier control points of object `i` are the `patch_count`
//! records after those of the Bézier objects before it ([`StoreMeta::patches_of`]).
//!
//! ## Triangle-mesh objects
//!
//! A mesh object's atlas uv `(s, t) ∈ [0, 1]²` spans a `k × k` grid of pages; page `(px, py)`,
//! with `px = min(⌊s·k⌋, k − 1)` and `py = min(⌊t·k⌋, k − 1)`, is sample map `first_patch +
//! py·k + px`, and its local uv is `(s·k − px, t·k − py)`. Each page is an ordinary m × m
//! sample map: texel `(x, y)` is centred at local `((x + ½)/m, (y + ½)/m)`, atlas texel
//! `(px·m + x, py·m + y)`. A sample point on a mesh records the page's map index as `patch`
//! and the local page uv as `uv`. The shading normal of a mesh is the interpolated vertex
//! normal (barycentric, renormalized); the geometric (face) normal serves sample-point and ray
//! offsets and side tests.
//!
//! ## Object textures
//!
//! A texture image's texel `(x, y)` is centred at texture coordinates `((x + ½)/w, 1 − (y + ½)/h)`
//! (v = 0 at the image's bottom row); a lookup is bilinear between the four nearest texel
//! centres and repeats in both directions (the bake resamples glTF clamp and mirror wraps
//! into the image). Base colour and emissive texels are sRGB-encoded and decoded (IEC
//! 61966-2-1) before filtering; the others are linear, `c/255`. The material at a point:
//! base colour = the base colour texture's RGB (the bake multiplied glTF's factor in), else
//! the object's base colour; roughness = G and metallic = B of the metallic-roughness texture
//! (factors multiplied in), else the material record's factors; the normal =
//! `normalize(t·x' + b·y' + n·z')` with `(x', y', z') = (2c − 1)·(scale, scale, 1)` of the
//! normal texture, `t`, `n` the interpolated tangent and normal (`t` made orthogonal to `n`)
//! and `b = w·(n × t)`; occlusion = `1 + strength·(R − 1)` (R clamped to `[0, 1]`), which
//! scales all the light the object reflects, diffuse and specular (glTF's sample viewer does
//! the same with image-based light), but not its emission; emission = the material record's
//! emission × the emissive texture's RGB.
//!
//! ## Sample points section
//!
//! sample_count records of 40 bytes ([`SamplePoint`], `#[repr(C)]`): `f32`×3 position (the
//! offset point, world space), `f32`×3 normal (the unit direction of the offset: the position
//! is base point + ε·normal; a patch's normal, or a mesh triangle's geometric normal on the side
//! of its shading normal; bakes before 2026-11-26 stored a mesh's interpolated normal here), `f32`×2
//! uv on the patch, or local uv on the atlas page (each in `[0, 1]`), `u32` patch (global map
//! index), `u32` object. Floats finite;
//! `object < object_count`; `patch` inside that object's patch range.
//!
//! ## Sample maps section
//!
//! Uncompressed, for zero-copy upload: patch-major, then row `y` (v), then column `x` (u);
//! texel `(x, y)` is centred at `u = (x + 0.5)/m`, `v = (y + 0.5)/m`. Each texel holds 4
//! indices (`u16` or `u32` per the header), sorted nearest first; a missing entry is `0xFFFF`
//! (`u16`) or `0xFFFF_FFFF` (`u32`) and may appear only after all present ones. Every present
//! index is `< sample_count`. In memory, missing entries read as [`INVALID_INDEX`].
//!
//! ## Cube payload section
//!
//! cube_count *records*, in cube order, each starting at a multiple of 8:
//!
//! | bytes | content |
//! |------:|---------|
//! | 4     | `u32` record magic `"OSCR"` |
//! | 4     | `u32` cube index |
//! | 144   | per face (6): `u64` compressed size, `u64` raw size, `u64` checksum of the frame |
//! | 8     | `u64` checksum of the record's bytes 0..152 |
//! | …     | the six zstd frames, back to back, faces in layer order +X, −X, +Y, −Y, +Z, −Z |
//! | 0–7   | zero padding to a multiple of 8 |
//!
//! Each face is one independent zstd frame that decompresses to exactly the *filtered size*:
//! the *raw size* `T (+ n² × 4 with the distance channel)`, where the texel part `T` is `n² ×
//! bytes_per_texel` (4, 8, 16) for RGB9E5, RGBA16F, RGBA32F and `⌈n/4⌉² × 16` for BC6H,
//! except with filter 3 on RGB9E5, where `T` is `n² × ⌈(5 + 3k) / 8⌉` for the metadata's
//! `mantissa_bits` k, and, from version 6, with filters 1 to 3, where the distance part is
//! `n² × 2` (see "Distance lattice"). The *raw face* is the `n²` encoded texels (row 0 first,
//! column 0 first; see [`cube`] for the orientation) — for BC6H the `⌈n/4⌉²` 16-byte blocks,
//! block row 0 first, each covering 4×4 texels (see "BC6H") — then, with the distance
//! channel, `n²` `f32` distances to the first hit (`f32::MAX` where the ray escaped; from
//! version 6 every distance lies on the distance lattice). With filter 0 the frame holds the
//! raw face itself; with filter 1, 2 or 3 it holds the raw face transformed as "Face
//! filters" describes, and readers undo the filter. The records make
//! a partial file recoverable without its table of contents ([`StoreWriter::resume`]). Cube
//! `sample_count`, if the environment flag is set, is an environment map captured at the
//! object's centre.
//!
//! ## Table of contents
//!
//! cube_count × 6 entries of 32 bytes — `u64` frame offset, `u64` compressed size, `u64` raw
//! size, `u64` frame checksum — cube-major, faces in layer order; then a `u64` checksum of all
//! the entries. Readers check: raw size equals the face raw size; compressed size in
//! `1..=ZSTD_compressBound(raw)`; face 0 of each cube starts 160 bytes (its record header)
//! after the 8-aligned end of the previous cube (the payload start for cube 0); each further
//! face starts where the previous one ends; all frames lie inside the payload, which ends at
//! the 8-aligned end of the last cube. Frames are checked against their checksum on every read
//! and must decompress to exactly their filtered size (decompression writes into a buffer of
//! that size, so a frame can never expand further).
//!
//! ## Face filters
//!
//! A filter is a lossless, reversible transform of a raw face, defined on every byte string of
//! the right size (decoders use wrapping arithmetic and never fail on content). Filter 0
//! (none) is the identity. Filter 1 (predict) transforms the texel part (`n² × bytes_per_texel`
//! bytes) and the distance part (`n² × 4` bytes) separately, each in place in the same byte
//! range. Notation: `t = n²`; texel `i = y·n + x`; texels are visited in order `i = 0..t`;
//! the prediction neighbours of texel `(x, y)` are `(a, b)` = (left `i−1`, above `i−n`), both
//! the left texel in row 0, both the texel above in column 0, none for texel (0, 0);
//! predictions use the *original* values of `a` and `b` (already reconstructed when decoding).
//! `>>` is a logical shift, `/` floor division, all values unsigned unless said otherwise.
//!
//! **RGB9E5** (`u32` texel `v`: `e = v >> 27`, mantissas `R = v & 511`, `G = (v >> 9) & 511`,
//! `B = (v >> 18) & 511`). `rescale(m, e_from, e_to)` = `min(511, m · 2^(e_from − e_to))` if
//! `e_from ≥ e_to`, else `(m + 2^(k−1)) >> k` with `k = e_to − e_from`. For texel `i` with
//! exponent `e` and neighbours with `(e_a, R_a, G_a, B_a)`, `(e_b, …)`:
//!
//! * `pG = (rescale(G_a, e_a, e) + rescale(G_b, e_b, e)) >> 1`; 0 without neighbours.
//! * for `C` in R, B: `s = G_a + G_b`; if `s = 0`, `pC = (rescale(C_a, e_a, e) +
//!   rescale(C_b, e_b, e)) >> 1`; else `pC = min(511, (G · (C_a + C_b) · ⌊2²⁰ / s⌋ + 2¹⁹) >> 20)`
//!   (64-bit product; `G` is this texel's green mantissa, so green is decoded first); 0 without
//!   neighbours.
//! * residual `zC = zigzag9((C − pC) mod 512)` for C in R, G, B, where `zigzag9(r)` = `2r` if
//!   `r < 256`, else `2(512 − r) − 1` (a 9-bit value). Decoding: `C = (pC + unzigzag9(zC))
//!   mod 512`.
//!
//! Output: four byte planes of `t` bytes each: plane 0 byte `i` = `e | (zR >> 8) << 5 |
//! (zG >> 8) << 6 | (zB >> 8) << 7`; planes 1, 2, 3 = `zG & 255`, `zR & 255`, `zB & 255`.
//!
//! **RGBA16F / RGBA32F** (`W` = 2 / 4 bytes; each channel's bit pattern read as a `W`-byte
//! unsigned integer; arithmetic mod `2^(8W)`). For texel `i` with channels `R, G, B, A`:
//! `pG = G_a`, `pA = A_a` (0 without neighbours); for `C` in R, B: `pC = G + ⌊(d_a + d_b) /
//! 2⌋` with `d = C − G` of the neighbour as a signed 64-bit difference of the unsigned
//! patterns (`pC = G` without neighbours). Residual `zC = zigzag(C − pC)`, where the `W`-byte
//! residual is read as a signed `W`-byte integer `s` and `zigzag` gives `2s` for `s ≥ 0`,
//! `−2s − 1` otherwise. Output: `4W` byte planes of `t` bytes, channels in the order G, R, B,
//! A, each channel's residual as `W` planes, least significant byte first: plane `k·W + j`,
//! byte `i` = byte `j` of texel `i`'s residual of the `k`-th channel of that order.
//!
//! **Distance plane, versions 1 to 5** (`u32` bit patterns `D` of the `f32` distances, mod
//! 2³²): `pD = D_a` (0 for texel (0, 0)); `z = zigzag(D − pD)` as above with `W = 4`; four
//! byte planes of `t` bytes, plane `j` = byte `j` of `z` (least significant first).
//!
//! **Distance plane, version 6 and later** (filters 1, 2 and 3 alike): each distance's
//! lattice code `c` (see "Distance lattice"), predicted from the codes of its left `a`, upper
//! `b` and upper-left `d` neighbours by the median edge detector: `p = min(a, b)` if `d ≥
//! max(a, b)`, `max(a, b)` if `d ≤ min(a, b)`, else `a + b − d`; in row 0 `p = a`, in column 0
//! `p = b`, at texel (0, 0) `p = 0`. `z = zigzag((c − p) mod 2¹⁶)` with `W = 2`; two byte
//! planes of `t` bytes, plane 0 the low bytes of `z`, plane 1 the high bytes. Decoding: `c =
//! (p + unzigzag(z)) mod 2¹⁶`, predictions from the codes so decoded, each code to its
//! distance as "Distance lattice" says. A distance off the lattice cannot be filtered
//! ([`Error::UnquantizedDistance`]).
//!
//! **Filter 2 (predict-rows)** is filter 1 except for RGB9E5 texels: RGBA16F, RGBA32F and
//! the distance plane are transformed exactly as filter 1 does, and the RGB9E5 output planes,
//! `zigzag9` and decoding order (green, then red and blue) are those of filter 1; only the
//! predictions `pG`, `pR`, `pB` differ. They are computed in IEEE-754 binary32 arithmetic,
//! every operation rounded to nearest-even, in the order written (no fused multiply-add):
//!
//! * the *value* of channel `C` of a texel with exponent `e` is `V_C = C · 2^e` (exact);
//! * taps: for `y ≥ 1`, `a = (max(x−1, 0), y−1)`, `b = (x, y−1)`, `c = (min(x+1, n−1), y−1)`
//!   (the row above, edge texels repeated); for `y = 0`, `x ≥ 1`, `a = b = c = (x−1, 0)` (the
//!   left texel); texel (0, 0) has no taps and takes `S_R = S_G = S_B = 0`;
//! * sums `S_C = (V_C(a) + 2·V_C(b)) + V_C(c)` for C in R, G, B;
//! * `q = 2^(−e−2)` for the texel's own exponent `e`; `round(x) = trunc(min(x + 0.5, 511))`
//!   (an integer in 0..=511; the sum `x + 0.5` is rounded to binary32 first);
//! * `pG = round(S_G · q)`;
//! * for C in R, B: `pC = round(S_C · q)` if `S_G = 0`, else `pC = round(G · (S_C / S_G))`,
//!   `G` this texel's green mantissa (as binary32);
//! * then each of `pG`, `pR`, `pB` is rounded to the store's *mantissa lattice*: with the
//!   metadata's `mantissa_bits` k and `s = 2^(9 − k)`, `p ← min((p + ⌊s/2⌋) & ¬(s − 1), 512 − s)`
//!   (integer arithmetic; the identity for k = 9, so version-1 stores and lossless ones are
//!   unaffected). Decoders take k from the metadata. The transform stays lossless for every
//!   input; texels quantized to k bits (see "Quantized RGB9E5") leave residuals that are
//!   multiples of `s`.
//!
//! **BC6H texels** (filters 1, 2 and 3): the blocks are left unchanged (the identity on the
//! texel part); the distance plane is transformed as in filter 1. (Byte planes of the blocks,
//! plane `j` = byte `j` of every block, compressed worse: see "BC6H".)
//!
//! Every row after the first depends only on the row above, so decoders reconstruct a row in
//! vector registers without a texel-to-texel dependency; filter 1's left neighbour chains
//! the texels of a row. Filter 1 ignores `mantissa_bits`.
//!
//! **Filter 3 (predict-packed)** is filter 2 except for the RGB9E5 texel part, which it
//! stores in fewer bytes when the store keeps `k = mantissa_bits` ≤ 6 bits (writers use it
//! only then; it is defined for every k in 1..=9). Its input texels must lie on the mantissa
//! lattice (every mantissa a multiple of `s = 2^(9 − k)`; writers quantize first and refuse
//! others with [`Error::Unquantized`]), and every decoded texel does. With the predictions
//! `pG`, `pR`, `pB` of filter 2 (lattice-rounded, so multiples of `s` too):
//!
//! * `q_C = ((C − pC) mod 512) / s`, a `k`-bit number of lattice steps, for C in R, G, B;
//! * `zk(q) = 2q` if `q < 2^(k−1)`, else `2(2^k − q) − 1` (zig-zag in `k` bits);
//! * the texel's *code* is the `(5 + 3k)`-bit number `e | zk(q_G) << 5 | zk(q_R) << (5 + k) |
//!   zk(q_B) << (5 + 2k)`;
//! * output: `P = ⌈(5 + 3k) / 8⌉` byte planes of `t` bytes, plane `j` byte `i` = bits `8j ..
//!   8j + 7` of texel `i`'s code (P = 1, 2, 2, 3, 3, 3, 4, 4, 4 for k = 1 … 9).
//!
//! Decoding: take `e` and the three `zk` fields from the code (bits above `5 + 3k` ignored),
//! `q = (z >> 1) XOR −(z AND 1)` in `k` bits, then `C = (pC + q · s) mod 512`, green first as
//! in filter 2. The distance plane follows the texel planes, transformed as in filter 1.
//!
//! Why the filters: the predictors shrink smooth radiance, but a bake's cube maps are
//! dominated by Monte Carlo noise, which no lossless filter removes; coarser lattices (k < 9)
//! leave less noise, and at k ≤ 6 filter 3's packed codes beat filter 2's zero-filled
//! mantissas, so writers use filter 3 there. Bytes per texel for every encoding, filter and k
//! are measured in docs/measurements.md ("Store sizes", "Quantized RGB9E5";
//! `cargo bench --bench store`).
//!
//! ## Encodings and measured accuracy
//!
//! See [`encoding`] for the bit layouts. Radiance must be finite and non-negative; values above
//! the largest finite value (RGB9E5 65408, RGBA16F and BC6H 65504) are clamped to it and
//! counted in [`EncodeStats::clamped_texels`]. RGBA32F is exact. BC6H's error depends on the
//! texels sharing a block, not on single values: see "BC6H". Measured by `tests/accuracy.rs` over
//! 20 001 log-spaced values in 1e-4..6e4 times the colour ratios (1,1,1), (1,0.5,0.25),
//! (1,1e-3,0), (0.2,1,0.7), (0.01,0.1,1) (100 005 texels):
//!
//! | encoding | largest channel: max / mean relative error | any channel, error relative to the largest channel: max | each channel, relative error: max / mean |
//! |----------|-------------------------------|------------------|--------------------|
//! | RGB9E5   | 1.935e-3 / 7.04e-4 (bound 2⁻⁹ = 1.953e-3) | 1.940e-3 (bound 2⁻⁹) | 1.0 / 5.6e-2 (channels far below the largest share its exponent and lose precision, down to 0) |
//! | RGBA16F  | 4.84e-4 / 1.76e-4 | 4.84e-4 | 4.88e-4 / 1.76e-4 for channels ≥ 6.1e-5 (bound 2⁻¹¹ = 4.883e-4; below, absolute error ≤ 2⁻²⁵) |
//!
//! ## BC6H
//!
//! Encoding 3 stores each face as unsigned BC6H blocks (`BC6H_UF16`: Vulkan
//! `BC6H_UFLOAT_BLOCK`, wgpu `Bc6hRgbUfloat`), 16 bytes per 4×4 texels, so a GPU with BC
//! texture compression can sample the blocks as they are. A face whose side `n` is not a
//! multiple of 4 is padded to `4⌈n/4⌉` by edge replication before encoding (texel `(x, y)`
//! beyond the face takes texel `(min(x, n−1), min(y, n−1))`); decoders crop the padding. The
//! values a reader returns are the BC6H specification's (D3D11 functional specification,
//! Khronos Data Format Specification "BC6H"): the binary16 bit patterns its unsigned decoder
//! produces, converted exactly to `f32` (at most 65504; never infinite, NaN or negative).
//! Radiance above 65504 is clamped to it and counted, as for RGBA16F. A block whose 5-bit mode
//! field is reserved (`0b10011`, `0b10111`, `0b11011`, `0b11111`) is invalid in a store:
//! [`Store::read_face_raw`] and [`Store::read_face`] return [`Error::ReservedBc6hMode`] naming
//! the cube, face and block. `mantissa_bits` is 9. See [`bc6h`] for the encoder and decoder.
//!
//! The writer's encoder is the `block_compression` crate's port of Intel's ISPC BC6H encoder
//! at [`bc6h::Quality::DEFAULT`] (`basic`): nearly the error of the slowest preset at a small
//! part of its time. BC6H is lossy: a 4×4 block with two endpoints and 8 or 16 interpolation
//! steps cannot follow a bake's per-texel Monte Carlo noise, while smooth radiance stays within
//! a few percent per texel (`tests/bc6h.rs`). The encoder presets' times and errors, the error
//! per texel and the bytes per texel on disk are measured in docs/measurements.md ("BC6H";
//! `cargo run --release -p oslf-format --example bc6h_quality -- STORE`).
//!
//! ## Quantized RGB9E5
//!
//! With `mantissa_bits` = k < 9, every RGB9E5 texel of every cube was quantized before the
//! face filter: each channel's 9-bit mantissa `m` became `min(((m + s/2) >> (9 − k)) <<
//! (9 − k), 512 − s)` with `s = 2^(9 − k)`, the shared exponent unchanged
//! ([`encoding::quantize_rgb9e5`]). The unfiltered faces are still plain RGB9E5 (filter 2's
//! decoder needs k, see "Face filters"; the texels need nothing): every mantissa is a
//! multiple of `s`, 0 stays 0, and the
//! per-channel error is below `2^−k · 2^(e − 15)` (`2^−k` of the exponent's scale, on top of
//! the RGB9E5 rounding). `mantissa_bits` does not touch the distance plane (see "Distance
//! lattice").
//!
//! ## Distance lattice
//!
//! From version 6 every distance of the distance plane lies on the *distance lattice* of `k =
//! clamp(⌈log2 n⌉, 1, 8)` mantissa bits, `n` the cube resolution (n = 32 → 5, 64 → 6, 128 →
//! 7, ≥ 256 → 8; [`distance::distance_bits`]): its `f32` bit pattern `D` has its low `23 − k`
//! bits zero, or it is the no-hit value `f32::MAX`. Its *code* is `D >> (23 − k)` (an `(8 +
//! k)`-bit number: exponent and the top `k` mantissa bits), and `0xFF << k` (the code of +∞)
//! for `f32::MAX`. Decoding a code `c`: take `c mod 2^(8 + k)`; codes `≥ 0xFF << k` (only
//! `0xFF << k` is written) are `f32::MAX`, the others `c << (23 − k)`, so every code decodes
//! to a finite non-negative distance. The raw face keeps `f32` distances, so a reader decodes
//! the plane as in every version and the checksum of the decoded faces covers the lattice
//! values.
//!
//! Writers put each distance on the lattice by rounding its pattern to the nearest multiple
//! of `2^(23 − k)` (ties to even; [`distance::quantize_distance`]); zero and `f32::MAX` stay
//! exact, a finite value that would round to +∞ takes the largest finite lattice value. The
//! relative error is at most `2^−(k+1) ≤ 1 / (2n)` for normal values: a texel at the face
//! centre subtends about `2 / n` radians, so the rounding moves a lookup (from a point no
//! farther from the sample point than the hit) by at most a quarter of a texel. The runtime
//! samples distances as binary16 (`2^−11` relative), finer than any lattice. Measured in
//! docs/measurements.md ("Compact distances"): 2.35 bytes per texel for the `f32` planes
//! before, 0.45 on the lattice at 32², with the renders' error against the truth unchanged
//! within 0.05 L*.
//!
//! ## Checksum of the decoded faces
//!
//! The frame checksums cover the compressed bytes, which decode differently under another
//! face filter id or `mantissa_bits`. Header bytes 180..188 (version 3 and later) hold the xxh3-64 of
//! the concatenation of the xxh3-64 checksums (`u64`, 8 bytes each) of every *raw face* (the
//! decompressed, unfiltered face: encoded texels, then the distance plane), cube-major, faces
//! in layer order: `cube_count × 6 × 8` bytes hashed, nothing for a store without cubes.
//! [`Store::verify`] decodes every face and checks it ([`Error::DecodedChecksum`]); opening a
//! store does not.
//!
//! ## Padding
//!
//! The padding regions are the 0–7 bytes after the metadata, the sample points and the sample
//! maps (up to the next section's 8-aligned start) and the 0–7 bytes after the last frame of
//! each cube record (up to the next record, or the table of contents after the last one). All
//! are zero; [`Store::verify`] checks every one and names the first non-zero byte's offset
//! ([`Error::NonZeroPadding`]). The header's reserved bytes are checked on open.
//!
//! ## Versions
//!
//! Version 2 added `mantissa_bits` to the metadata (4 bytes after the scene hash); version 3
//! the checksum of the decoded faces (header bytes 180..188, reserved zero before); version 4
//! the BC6H encoding (tag 3, refused in older stores with [`Error::EncodingVersion`] from the
//! header, [`Error::InvalidMetadata`] from the metadata); version 5 triangle-mesh objects: a
//! `u32` kind after each object record (and, for a mesh, its mesh record), the header's and
//! metadata's patch_count counting sample maps (patches plus atlas pages), and control points
//! for the Bézier objects' patches only; version 6 the distance lattice (distances rounded to
//! it, and filters 1 to 3 storing their codes in two byte planes instead of the `f32`
//! patterns in four; see "Distance lattice"); version 7 the material record after each object
//! record (stores before it read as Lambertian objects of their base colour); version 8 the
//! texture record after each material record (older stores read as untextured). Readers accept
//! versions [`MIN_VERSION`] (1) to [`VERSION`] (8) and refuse others ([`Error::UnsupportedVersion`]); a
//! version-1 metadata section has no `mantissa_bits` and reads as 9; versions 1 and 2 have no
//! checksum of the decoded faces, so [`Store::verify`] checks their frames but not what they
//! decode to; before version 5 every object is Bézier (no kind field). Every other byte of the
//! layout is the same in all versions: a version-3 store is a version-4 store that holds no
//! BC6H, and a version-6 store without a distance channel is laid out as a version-5 one.
//! Writers write version 8; [`StoreWriter::resume`] continues partial files of versions 2 to
//! 4 as version 4 (their shared layout; such a bake cannot hold mesh objects), of version 5
//! as version 5, of version 6 as version 6 (these cannot hold a material other than
//! Lambertian), of version 7 as version 7 (it cannot hold textures) and of version 8 as
//! version 8. A continued version-2 to version-5 file keeps
//! `f32` distance planes: the cubes appended to it have their distances on the lattice (as
//! [`encode_cube`] makes them) but filtered as `f32` patterns.
//!
//! ## Shards
//!
//! A bake split over machines writes *shard files*, each holding a share of the cubes plus
//! everything before the cube payload; [`shard::merge`] joins them into the store a single
//! bake writes, byte for byte. Their layout is specified in [`shard`]; a store never
//! contains shard data.
//!
//! ## Limits and host requirements
//!
//! Cube resolution ≤ [`MAX_CUBE_RESOLUTION`] (16384), sample-map resolution ≤
//! [`MAX_SAMPLE_MAP_RESOLUTION`] (16384), object names ≤ 4096 bytes, cube count ≤ 2³²−1.
//! The zero-copy views ([`Store::sample_points`], [`SampleMapView::as_u16`]) reinterpret the
//! little-endian bytes in place, so [`Store::open`] and [`Store::from_bytes`] return
//! [`Error::BigEndianHost`] on big-endian hosts. The writer works on any host.
//!
//! ## Writing
//!
//! [`StoreWriter`] writes `<path>.partial` beside the target, appends cube records as they
//! come ([`encode_cube`] is pure, so encode in parallel), syncs every 64 cubes or 64 MiB, and
//! `finish()` writes the table of contents, patches the header (flags, payload size, TOC
//! position, file size, checksum of the decoded faces — bytes 12..16, 120..152 and 180..188),
//! syncs, renames over the target and syncs the directory: a crash leaves either no store or a
//! complete one under the final name.

pub mod bc6h;
pub(crate) mod bytes;
pub mod cube;
mod differences;
pub mod distance;
pub mod encoding;
mod encoding_kind;
mod error;
mod file_stamp;
pub mod filter;
pub mod header;
pub mod meta;
mod output_file;
mod prefix;
mod resume;
pub mod sample_map;
pub mod shard;
pub mod store;
pub mod textures;
pub mod toc;
pub mod writer;

pub use cube::{encode_cube, encode_cube_with_filter, CubeImage, EncodeStats, EncodedCube};
pub use distance::DistancePlane;
pub use encoding_kind::Encoding;
pub use error::Error;
pub use filter::Filter;
pub use meta::{
    BakeParams, CameraInfo, MeshInfo, ObjectInfo, ObjectMaterial, Patch, SamplePoint, StoreMeta,
};
pub use output_file::{check_not_input, check_output, same_file};
pub use sample_map::{IndexWidth, SampleMapView, SampleMaps, INVALID_INDEX};
pub use shard::{ShardSpec, ShardSummary, ShardWriter};
pub use store::{Store, StoreAccess, VerifyReport};
pub use textures::{ObjectTextures, TextureImage, TextureKind};
pub use toc::FaceEntry;
pub use writer::{StoreSummary, StoreWriter};

/// The first 8 bytes of every store.
pub const MAGIC: [u8; 8] = *b"OSLFSTOR";
/// The first 8 bytes of every shard file ([`shard`]); a store reader that finds them says the
/// file is a shard.
pub const SHARD_MAGIC: [u8; 8] = *b"OSLFSHRD";
/// The format version, header bytes 8..12: format 1.0, major version 1 in the high 16 bits,
/// minor 0 in the low 16. The only version this crate writes and reads.
pub const VERSION: u32 = 0x0001_0000;
/// Version numbers 1 to 8 in header bytes 8..12 mark stores written by development builds
/// before format 1.0; readers refuse them with [`Error::UnsupportedVersion`], which says to
/// bake the scene again.
pub const LAST_DEVELOPMENT_VERSION: u32 = 8;

/// `version` as "major.minor" (`VERSION` is "1.0").
pub fn version_name(version: u32) -> String {
    format!("{}.{}", version >> 16, version & 0xffff)
}
/// Largest cube-map face resolution a store may declare.
pub const MAX_CUBE_RESOLUTION: u32 = 16384;
/// Largest sample-map resolution a store may declare.
pub const MAX_SAMPLE_MAP_RESOLUTION: u32 = 16384;
/// Largest object name, in bytes.
pub const MAX_NAME_BYTES: usize = 4096;
