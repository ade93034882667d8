//! The stage's items for `kernel!` (src/cpu/kernel.rs), apart from
//! texture.rs's re-export of the single-precision ones, so that the
//! precisions' modules, which expand them, import nothing that imports them.

/// The stage's items, expanded into the module that invokes it (`kernel!`).
macro_rules! texture {
    () => {
        use crate::texture::LINEAR_ONE;

        const WRAP_MIRRORED: u32 = 1;
        const WRAP_CLAMP: u32 = 2;

        /// The scene's texture store (`texture::TextureStore::words`), what the
        /// shader's `textures` binding holds.
        #[derive(Clone, Copy, Debug)]
        pub struct Textures<'a> {
            pub words: &'a [u32],
        }

        /// A texture coordinate brought into one period of its wrap mode.
        #[inline(always)]
        pub fn wrap_coordinate(u: Real, mode: u32) -> Real {
            let x = if u.abs() <= 1e30 { u } else { 0.0 };
            if mode == WRAP_CLAMP {
                return x.clamp(0.0, 1.0);
            }
            if mode == WRAP_MIRRORED {
                return rounded(x - 2.0 * (x * 0.5).floor());
            }
            rounded(x - x.floor())
        }

        /// A texel index as the wrap mode reads it.
        #[inline(always)]
        pub fn wrap_texel(i: i32, size: i32, mode: u32) -> i32 {
            if mode == WRAP_CLAMP {
                return i.clamp(0, size - 1);
            }
            if mode == WRAP_MIRRORED {
                let period = 2 * size;
                let k = ((i % period) + period) % period;
                return if k >= size { period - 1 - k } else { k };
            }
            ((i % size) + size) % size
        }

        /// A wrapped coordinate in 1/256 texels from the first texel's centre.
        #[inline(always)]
        pub fn texel_position(u: Real, size: u32) -> i32 {
            (u * (size * 256) as Real).floor() as i32 - 128
        }

        /// A fixed-point sum (1.0 = 2^31) as floats.
        #[inline(always)]
        pub fn fixed_to_float(sum: [u32; 4]) -> Vec4 {
            Vec4::from_array(sum.map(|s| {
                ((s >> 16) as Real * 65536.0 + (s & 65535) as Real) * (1.0 / 2147483648.0)
            }))
        }

        /// log2 |x| from the float's bits, in 1/4096.
        #[inline(always)]
        pub fn log2_fixed(x: Real) -> i32 {
            // Exponent and the top 12 stored mantissa bits, less the bias.
            (x.abs().to_bits() >> (Real::MANTISSA_DIGITS - 13)) as i32 - ((Real::MAX_EXP - 1) << 12)
        }

        /// `x` as rounded here: the identity, as Rust neither fuses a multiply
        /// into an add nor reassociates (the shader's select stops its compiler).
        #[inline(always)]
        pub fn rounded(x: Real) -> Real {
            x
        }

        /// a·b − c·d, each product and the difference rounded on its own.
        #[inline(always)]
        pub fn difference_of_products(a: Real, b: Real, c: Real, d: Real) -> Real {
            rounded(rounded(a * b) - rounded(c * d))
        }

        /// The texture coordinate at barycentrics (b1, b2).
        #[inline(always)]
        pub fn interpolate_uv(uv0: Vec2, uv1: Vec2, uv2: Vec2, b1: Real, b2: Real) -> Vec2 {
            let e1 = uv1 - uv0;
            let e2 = uv2 - uv0;
            Vec2::new(
                uv0.x + (b1 * e1.x + b2 * e2.x),
                uv0.y + (b1 * e1.y + b2 * e2.y),
            )
        }

        impl Textures<'_> {
            /// Texel (x, y) of the level whose entry starts at word `level`, as
            /// linear RGBA in 1/LINEAR_ONE (RGB through the table at word `table`).
            #[inline(always)]
            pub fn texel_linear(&self, level: u32, x: i32, y: i32, table: u32) -> [u32; 4] {
                let w = self.words;
                let at = w[level as usize] + y as u32 * w[level as usize + 1] + x as u32;
                let word = w[at as usize];
                let decode = |shift: u32| w[(table + ((word >> shift) & 255)) as usize];
                [
                    decode(0),
                    decode(8),
                    decode(16),
                    ((word >> 24) * LINEAR_ONE + 127) / 255,
                ]
            }

            /// One level's filtered value at the wrapped `uv`, weighted in 1/65536.
            #[inline(always)]
            pub fn level_sum(
                &self,
                level: u32,
                uv: Vec2,
                wrap_u: u32,
                wrap_v: u32,
                bilinear: bool,
                table: u32,
            ) -> [u32; 4] {
                let width = self.words[level as usize + 1] as i32;
                let height = self.words[level as usize + 2] as i32;
                let px = texel_position(uv.x, width as u32);
                let py = texel_position(uv.y, height as u32);
                if !bilinear {
                    let x = wrap_texel((px + 128) >> 8, width, wrap_u);
                    let y = wrap_texel((py + 128) >> 8, height, wrap_v);
                    return self.texel_linear(level, x, y, table).map(|c| c * 65536);
                }
                let x0 = wrap_texel(px >> 8, width, wrap_u);
                let x1 = wrap_texel((px >> 8) + 1, width, wrap_u);
                let y0 = wrap_texel(py >> 8, height, wrap_v);
                let y1 = wrap_texel((py >> 8) + 1, height, wrap_v);
                let fx = (px & 255) as u32;
                let fy = (py & 255) as u32;
                let taps = [
                    (
                        self.texel_linear(level, x0, y0, table),
                        (256 - fx) * (256 - fy),
                    ),
                    (self.texel_linear(level, x1, y0, table), fx * (256 - fy)),
                    (self.texel_linear(level, x0, y1, table), (256 - fx) * fy),
                    (self.texel_linear(level, x1, y1, table), fx * fy),
                ];
                std::array::from_fn(|c| taps.iter().map(|(t, weight)| t[c] * weight).sum())
            }

            /// The f32 stored at word `at`, in this precision.
            fn word_f32(&self, at: u32) -> Real {
                f32::from_bits(self.words[at as usize]) as Real
            }

            /// The slot's UV transform: uv' = M · (u, v, 1).
            #[inline(always)]
            pub fn transform_uv(&self, slot: u32, uv: Vec2) -> Vec2 {
                let m: [Real; 6] = std::array::from_fn(|i| self.word_f32(slot + i as u32));
                Vec2::new(
                    (m[0] * uv.x + m[1] * uv.y) + m[2],
                    (m[3] * uv.x + m[4] * uv.y) + m[5],
                )
            }

            /// The texture of the slot at word `slot`, at `uv`, at level of detail
            /// `lod` (1/256 levels; ≤ 0 magnified), as linear RGBA.
            pub fn sample_texture(&self, slot: u32, uv: Vec2, lod: i32) -> Vec4 {
                let flags = self.words[slot as usize + 8];
                let levels = self.words[slot as usize + 7];
                let table = self.words[slot as usize + 9];
                let count = (flags >> 8) & 255;
                let wrap_u = flags & 3;
                let wrap_v = (flags >> 2) & 3;
                let t = self.transform_uv(slot, uv);
                let w = Vec2::new(wrap_coordinate(t.x, wrap_u), wrap_coordinate(t.y, wrap_v));
                if lod <= 0 {
                    return fixed_to_float(self.level_sum(
                        levels,
                        w,
                        wrap_u,
                        wrap_v,
                        flags & 16 != 0,
                        table,
                    ));
                }
                let bilinear = flags & 32 != 0;
                if flags & 64 == 0 {
                    return fixed_to_float(
                        self.level_sum(levels, w, wrap_u, wrap_v, bilinear, table),
                    );
                }
                let level = (lod >> 8) as u32;
                if level + 1 >= count {
                    return fixed_to_float(self.level_sum(
                        levels + 4 * (count - 1),
                        w,
                        wrap_u,
                        wrap_v,
                        bilinear,
                        table,
                    ));
                }
                let f = (lod & 255) as u32;
                let finer = self.level_sum(levels + 4 * level, w, wrap_u, wrap_v, bilinear, table);
                let coarser =
                    self.level_sum(levels + 4 * (level + 1), w, wrap_u, wrap_v, bilinear, table);
                fixed_to_float(std::array::from_fn(|c| {
                    (finer[c] >> 8) * (256 - f) + (coarser[c] >> 8) * f
                }))
            }

            /// Ray-cone level of detail in 1/256 levels (the shader's comment, and
            /// docs/textures.md, derive it).
            #[allow(clippy::too_many_arguments)]
            #[inline(always)]
            pub fn texture_lod(
                &self,
                slot: u32,
                p0: Vec3,
                p1: Vec3,
                p2: Vec3,
                uv0: Vec2,
                uv1: Vec2,
                uv2: Vec2,
                dir: Vec3,
                cone_width: Real,
            ) -> i32 {
                let e1 = p1 - p0;
                let e2 = p2 - p0;
                let n = Vec3::new(
                    difference_of_products(e1.y, e2.z, e1.z, e2.y),
                    difference_of_products(e1.z, e2.x, e1.x, e2.z),
                    difference_of_products(e1.x, e2.y, e1.y, e2.x),
                );
                let nn = (n.x * n.x + n.y * n.y) + n.z * n.z;
                let nd = (n.x * dir.x + n.y * dir.y) + n.z * dir.z;
                let a = uv1 - uv0;
                let b = uv2 - uv0;
                let uv_area = difference_of_products(a.x, b.y, a.y, b.x);
                let texel_area = self.word_f32(slot + 6);
                let four_lambda = 2 * log2_fixed(uv_area)
                    + 2 * log2_fixed(texel_area)
                    + log2_fixed(nn)
                    + 4 * log2_fixed(cone_width)
                    - 4 * log2_fixed(nd);
                four_lambda >> 6
            }
        }
    };
}
pub(crate) use texture;
