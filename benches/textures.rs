//! What a texture lookup costs on the CPU twin (docs/benchmarks.md,
//! "Textures"): `sample_texture` magnified (bilinear, one level) and
//! minified (trilinear, two levels) at random points of a 1024² texture,
//! and `texture_lod` of random triangles.
//!
//!     cargo bench --bench textures

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::{Vec2, Vec3};
use lambert::cpu::texture::Textures;
use lambert::loading::material::{IDENTITY_UV_TRANSFORM, Sampler, TextureUse};
use lambert::probe::Rng;
use lambert::texture::{DecodedImage, TextureStore};

const SAMPLES: usize = 1 << 16;

fn textures(c: &mut Criterion) {
    let mut rng = Rng(7);
    let side = 1024;
    let image = DecodedImage {
        width: side,
        height: side,
        rgba: (0..4 * side * side).map(|_| rng.next_u64() as u8).collect(),
        format: "PNG",
    };
    let mut store = TextureStore::default();
    let index = store.add_image(&image, "random".into());
    let slot = store.slot(
        index,
        &TextureUse {
            image: 0,
            sampler: Sampler::default(),
            transform: IDENTITY_UV_TRANSFORM,
        },
    );
    let twin = Textures {
        words: store.words(),
    };
    let uvs: Vec<Vec2> = (0..SAMPLES)
        .map(|_| Vec2::new(rng.unit() as f32 * 4.0, rng.unit() as f32 * 4.0))
        .collect();
    let lods: Vec<i32> = (0..SAMPLES)
        .map(|_| 1 + (rng.unit() * 2560.0) as i32)
        .collect();
    let mut group = c.benchmark_group("texture");
    group.throughput(Throughput::Elements(SAMPLES as u64));
    group.bench_function("bilinear", |b| {
        b.iter(|| {
            uvs.iter()
                .map(|&uv| twin.sample_texture(slot, black_box(uv), 0).x)
                .sum::<f32>()
        })
    });
    group.bench_function("trilinear", |b| {
        b.iter(|| {
            uvs.iter()
                .zip(&lods)
                .map(|(&uv, &lod)| twin.sample_texture(slot, black_box(uv), lod).x)
                .sum::<f32>()
        })
    });
    let p: Vec<Vec3> = (0..SAMPLES + 2)
        .map(|_| Vec3::new(rng.unit() as f32, rng.unit() as f32, rng.unit() as f32))
        .collect();
    group.bench_function("lod", |b| {
        b.iter(|| {
            (0..SAMPLES)
                .map(|i| {
                    twin.texture_lod(
                        slot,
                        p[i],
                        p[i + 1],
                        p[i + 2],
                        uvs[i].fract(),
                        uvs[(i + 1) % SAMPLES].fract(),
                        uvs[(i + 2) % SAMPLES].fract(),
                        Vec3::Z,
                        black_box(0.01),
                    )
                })
                .sum::<i32>()
        })
    });
    group.finish();
}

criterion_group!(benches, textures);
criterion_main!(benches);
