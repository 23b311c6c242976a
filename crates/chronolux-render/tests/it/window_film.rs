//! The tiled, disk-cached WindowFilm gives bit-identical frames for every memory budget,
//! keeps its memory under the budget, and cleans up its cache directory.

use chronolux_core::color::Rgb;
use chronolux_core::sampling::rng::Pcg32;
use chronolux_render::framework::window_film::{Contribution, FILM_TILE, WindowFilm};
use std::collections::BTreeMap;

/// 150×100 pixels: 3×2 tiles of 64², edge tiles clipped to 22 and 36 pixels.
const W: u32 = 150;
const H: u32 = 100;

/// Random batches over frames 0..6, with frames finished along the way (a sliding
/// window): (batches, frames finished after each batch).
fn workload(seed: u64) -> Vec<(Vec<Contribution>, Vec<u32>)> {
    let mut rng = Pcg32::new(seed, 7);
    let mut out = Vec::new();
    for step in 0..24u32 {
        let lo = step / 4;
        let n = 1 + (rng.next_u32() % 3000) as usize;
        let batch = (0..n)
            .map(|_| {
                let frame = lo + rng.next_u32() % 3;
                // Half the contributions in a few hot pixels, so pixels get many additions
                // whose order matters for the f32 sums.
                let pixel = if rng.next_f32() < 0.5 {
                    rng.next_u32() % 16 * 997 % (W * H)
                } else {
                    rng.next_u32() % (W * H)
                };
                Contribution {
                    frame,
                    pixel,
                    value: Rgb::new(rng.next_f32(), 3.0 * rng.next_f32(), 0.1 * rng.next_f32()),
                    weight: 0.1 + rng.next_f32(),
                    splat: rng.next_f32() < 0.3,
                }
            })
            .collect();
        let finished = if step % 4 == 3 { vec![lo] } else { vec![] };
        out.push((batch, finished));
    }
    out
}

/// The film's semantics written out one contribution at a time, per pixel in batch order.
#[derive(Default)]
struct Naive {
    frames: BTreeMap<u32, Vec<(Rgb, f32, Rgb)>>,
}

impl Naive {
    fn add(&mut self, c: &Contribution) {
        let f = self
            .frames
            .entry(c.frame)
            .or_insert_with(|| vec![(Rgb::ZERO, 0.0, Rgb::ZERO); (W * H) as usize]);
        let p = &mut f[c.pixel as usize];
        if c.splat {
            p.2 += c.value;
        } else {
            p.0 += c.value * c.weight;
            p.1 += c.weight;
        }
    }

    fn finish(&mut self, frame: u32, scale: f32) -> (Vec<Rgb>, Vec<f32>) {
        let n = (W * H) as usize;
        let Some(f) = self.frames.remove(&frame) else {
            return (vec![Rgb::ZERO; n], vec![0.0; n]);
        };
        let px = f
            .iter()
            .map(|(s, w, sp)| {
                let m = if *w > 0.0 { *s / *w } else { Rgb::ZERO };
                m + *sp * scale
            })
            .collect();
        (px, f.iter().map(|p| p.1).collect())
    }
}

fn bits(px: &[Rgb], w: &[f32]) -> Vec<u32> {
    px.iter()
        .flat_map(|p| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
        .chain(w.iter().map(|x| x.to_bits()))
        .collect()
}

/// Runs the workload through `film`, checking the resident bytes after every batch, and
/// returns every finished frame's bits (finish order) and the bits of the frames left
/// open at the end.
fn run(film: &mut WindowFilm, work: &[(Vec<Contribution>, Vec<u32>)], bound: u64) -> Vec<Vec<u32>> {
    let mut out = Vec::new();
    for (batch, finished) in work {
        film.add_batch(batch);
        assert!(
            film.resident_bytes() <= bound,
            "{} bytes resident, bound {bound}",
            film.resident_bytes()
        );
        for &f in finished {
            let (px, w) = film.finish(f, 0.25);
            out.push(bits(&px, &w));
        }
    }
    for f in film.open_frames() {
        let (px, w) = film.finish(f, 0.25);
        out.push(bits(&px, &w));
    }
    out
}

#[test]
fn spilling_film_is_bit_identical_to_the_in_memory_one_and_stays_in_budget() {
    let work = workload(3);
    let tile = WindowFilm::tile_bytes();

    // The reference: one contribution at a time, in batch order.
    let mut naive = Naive::default();
    let mut expected = Vec::new();
    for (batch, finished) in &work {
        batch.iter().for_each(|c| naive.add(c));
        for &f in finished {
            let (px, w) = naive.finish(f, 0.25);
            expected.push(bits(&px, &w));
        }
    }
    for f in naive.frames.keys().copied().collect::<Vec<_>>() {
        let (px, w) = naive.finish(f, 0.25);
        expected.push(bits(&px, &w));
    }

    let mut unbounded = WindowFilm::new(W, H);
    assert_eq!(run(&mut unbounded, &work, u64::MAX), expected);
    assert_eq!(unbounded.stats().bytes_written, 0);
    assert!(unbounded.cache_dir().is_none());

    let parent = std::env::temp_dir().join(format!("chronolux-film-test-{}", std::process::id()));
    // Two full tiles (3 frames × 6 tiles are open at once: forced spills), and a budget
    // below one tile (every tile switch spills).
    for budget in [2 * tile, 1000] {
        let mut film = WindowFilm::with_budget(W, H, budget, Some(&parent));
        // A tile over the budget is allowed only while a single tile is resident (budget
        // below one tile); the module doc's bound is max(budget, one tile).
        let bound = budget.max(tile);
        let got = run(&mut film, &work, bound);
        assert_eq!(got, expected, "budget {budget}");
        let s = film.stats();
        assert!(
            s.tile_misses > 0 && s.bytes_written > 0 && s.bytes_read > 0,
            "{s:?}"
        );
        // Peak: the resident bound plus the one tile `finish` reads back.
        assert!(s.peak_bytes <= bound + tile, "{s:?}");
        assert!(s.peak_bytes > 0);
        let dir = film.cache_dir().expect("spilled").to_path_buf();
        assert!(dir.starts_with(&parent) && dir.is_dir());
        assert!(film.open_frames().is_empty());
        drop(film);
        assert!(
            !dir.exists(),
            "cache directory {} left behind",
            dir.display()
        );
    }
    let _ = std::fs::remove_dir(&parent);
}

#[test]
fn batches_of_any_size_give_the_same_frame() {
    // The same contributions cut into different batches: one pixel's additions keep
    // their order, so the result is bit-identical.
    let work = workload(11);
    let all: Vec<Contribution> = work.iter().flat_map(|(b, _)| b.iter().copied()).collect();
    let tile = WindowFilm::tile_bytes();
    let mut whole = WindowFilm::with_budget(W, H, 3 * tile, None);
    whole.add_batch(&all);
    let mut pieces = WindowFilm::with_budget(W, H, 3 * tile, None);
    for c in all.chunks(777) {
        pieces.add_batch(c);
    }
    let frames = whole.open_frames();
    assert_eq!(frames, pieces.open_frames());
    for f in frames {
        let (a, aw) = whole.finish(f, 1.0);
        let (b, bw) = pieces.finish(f, 1.0);
        assert_eq!(bits(&a, &aw), bits(&b, &bw), "frame {f}");
    }
}

#[test]
fn untouched_frames_and_tiles_are_zero() {
    let mut film = WindowFilm::with_budget(W, H, WindowFilm::tile_bytes(), None);
    let (px, w) = film.finish(42, 1.0);
    assert_eq!(px.len(), (W * H) as usize);
    assert!(px.iter().all(|p| *p == Rgb::ZERO) && w.iter().all(|x| *x == 0.0));
    // One contribution in the last (clipped) tile of frame 3; a splat in frame 5 spills
    // frame 3's tile.
    let last = W * H - 1;
    film.add_batch(&[Contribution {
        frame: 3,
        pixel: last,
        value: Rgb::new(1.0, 2.0, 3.0),
        weight: 2.0,
        splat: false,
    }]);
    film.add_batch(&[Contribution {
        frame: 5,
        pixel: 0,
        value: Rgb::ONE,
        weight: 0.0,
        splat: true,
    }]);
    assert_eq!(film.open_frames(), vec![3, 5]);
    assert_eq!(film.stats().tiles_written, 1);
    let (px, w) = film.finish(3, 1.0);
    for (i, (p, x)) in px.iter().zip(&w).enumerate() {
        if i as u32 == last {
            assert_eq!((*p, *x), (Rgb::new(1.0, 2.0, 3.0), 2.0));
        } else {
            assert_eq!((*p, *x), (Rgb::ZERO, 0.0), "pixel {i}");
        }
    }
    let (px, w) = film.finish(5, 0.5);
    assert_eq!(px[0], Rgb::splat(0.5));
    assert!(w.iter().all(|x| *x == 0.0));
    assert!(px[1..].iter().all(|p| *p == Rgb::ZERO));
    // Taken out: finishing again gives zeros.
    let (px, _) = film.finish(3, 1.0);
    assert!(px.iter().all(|p| *p == Rgb::ZERO));
    assert!(film.open_frames().is_empty());
    assert_eq!(film.resident_bytes(), 0);
    assert_eq!(FILM_TILE, 64);
}

#[test]
fn filtered_and_sparse_batches_match_one_by_one_addition() {
    // `add_batch_where` equals adding the kept contributions one at a time, on both of
    // its grouping paths: the counting sort (the workload's 3-frame batches) and the sort
    // for a batch spread over a frame range far wider than itself (frames 0 and 10 000).
    let mut work = workload(5);
    let mut rng = Pcg32::new(9, 1);
    for (batch, _) in work.iter_mut().step_by(5) {
        for c in batch.iter_mut() {
            if rng.next_f32() < 0.2 {
                c.frame += 10_000;
            }
        }
    }
    let keep = |f: u32| f.is_multiple_of(2) || f >= 10_000;
    let mut naive = Naive::default();
    let mut film = WindowFilm::new(W, H);
    for (batch, _) in &work {
        for c in batch.iter().filter(|c| keep(c.frame)) {
            naive.add(c);
        }
        film.add_batch_where(batch, keep);
    }
    let frames = film.open_frames();
    assert_eq!(frames, naive.frames.keys().copied().collect::<Vec<_>>());
    assert!(frames.iter().any(|&f| f >= 10_000) && frames.iter().all(|&f| keep(f)));
    for f in frames {
        let (a, aw) = film.finish(f, 0.5);
        let (b, bw) = naive.finish(f, 0.5);
        assert_eq!(bits(&a, &aw), bits(&b, &bw), "frame {f}");
    }
}
