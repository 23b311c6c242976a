//! Direct and indirect light (`RenderedFrame::light`, the passes `direct`/`indirect`):
//! they add up to the beauty exactly, follow the documented convention, and only the
//! techniques that separate them write them.

use crate::bits;
use crate::source;
use chronolux_core::color::Rgb;
use chronolux_core::scene::desc::SceneDesc;
use chronolux_render::framework::integrator::RenderedFrame;
use chronolux_render::framework::sequence::SequenceRenderer;
use chronolux_render::registry::{self, BuildContext};
use serde_json::{Value, json};

const W: u32 = 24;
const H: u32 = 24;

fn renderer(method: &str, settings: Value) -> Box<dyn SequenceRenderer> {
    let t = registry::find(method).unwrap();
    let sets: Vec<(String, Value)> = settings
        .as_object()
        .unwrap()
        .iter()
        .map(|(k, v)| (k.clone(), v.clone()))
        .collect();
    let s = registry::resolve(t, None, &sets).unwrap_or_else(|e| panic!("{method}: {e}"));
    t.build(&s, &BuildContext::default()).unwrap()
}

/// Frame 4 of `desc` by `r`.
fn frame4_of(desc: SceneDesc, r: &mut dyn SequenceRenderer) -> RenderedFrame {
    let mut src = source(desc, W, H, 24.0, vec![4]);
    r.render_frame(&mut src, 4, &|_| {})
}

/// Frame 4 of the demo (the Cornell stage with its moving block and glossy materials).
fn frame4(r: &mut dyn SequenceRenderer) -> RenderedFrame {
    frame4_of(chronolux_core::scene::stage::demo(), r)
}

fn sum(v: &[Rgb]) -> f64 {
    v.iter().map(|p| (p.x + p.y + p.z) as f64).sum()
}

/// direct + indirect is the beauty, bit for bit (the driver forms the beauty as that sum).
fn assert_adds_up(name: &str, img: &RenderedFrame) {
    let l = img
        .light
        .as_ref()
        .unwrap_or_else(|| panic!("{name}: no light split"));
    let summed: Vec<Rgb> = l
        .direct
        .iter()
        .zip(&l.indirect)
        .map(|(d, i)| *d + *i)
        .collect();
    assert_eq!(bits(&summed), bits(&img.pixels), "{name}");
}

#[test]
fn path_direct_is_the_two_segment_image_and_adds_up_with_indirect() {
    // The Cornell box: Lambertian surfaces only (no delta lobe), lit from the ceiling.
    let path = |depth: u32| {
        frame4_of(
            chronolux_core::scene::stage::cornell_box(),
            &mut *renderer("path", json!({"spp": 4, "max_depth": depth, "seed": 3})),
        )
    };
    let (full, two) = (path(8), path(2));
    assert_adds_up("path, max_depth 8", &full);
    assert_adds_up("path, max_depth 2", &two);
    let (lf, l2) = (full.light.unwrap(), two.light.unwrap());
    // Paths of at most two segments (emission seen, and direct lighting) have at most one
    // scattering vertex: all direct, nothing indirect.
    assert!(l2.indirect.iter().all(|p| *p == Rgb::ZERO));
    // The box's surfaces have no delta lobe, so the direct light of the full render is
    // exactly what a two-segment render computes from the same sample streams: the
    // emission seen, the first vertex's light sample and the MIS-weighted emission its
    // BSDF sample hits, added in the same order.
    assert_eq!(bits(&lf.direct), bits(&l2.direct));
    // A closed room lit from the ceiling: the walls' interreflections are indirect light
    // (a fifth to a half of the direct light for albedos of 0.1 to 0.8: loose bounds).
    let (d, i) = (sum(&lf.direct), sum(&lf.indirect));
    assert!(i > 0.05 * d && i < d, "direct {d}, indirect {i}");
}

#[test]
fn dept_direct_is_per_pixel_and_indirect_comes_from_the_elements() {
    let dept = |photons: u64| {
        frame4(&mut *renderer(
            "dept",
            json!({"photons": photons, "spp": 2, "seed": 5}),
        ))
    };
    let (a, b) = (dept(4000), dept(16000));
    assert_adds_up("dept 4k", &a);
    assert_adds_up("dept 16k", &b);
    let (la, lb) = (a.light.unwrap(), b.light.unwrap());
    // Direct light is light sampling per pixel, independent of the photons; indirect is
    // the element solution, which they change.
    assert_eq!(bits(&la.direct), bits(&lb.direct));
    assert_ne!(bits(&la.indirect), bits(&lb.indirect));
    assert!(sum(&la.indirect) > 0.0);
}

#[test]
fn techniques_that_do_not_separate_light_say_so() {
    for (method, settings) in [("stbpt", json!({"spp": 1})), ("bdpt", json!({"spp": 1}))] {
        let mut r = renderer(method, settings);
        assert!(!r.separates_light(), "{method}");
        assert!(frame4(&mut *r).light.is_none(), "{method}");
    }
    for method in ["path", "dept", "dept-spatial", "spacetime-dept"] {
        let t = registry::find(method).unwrap();
        let r = t.build(&t.defaults(), &BuildContext::default()).unwrap();
        assert!(r.separates_light(), "{method}");
    }
    // Asking a technique that does not separate them is an error; `all` drops them.
    use chronolux_render::framework::aov::PassSet;
    let named = PassSet::parse("albedo,direct").unwrap();
    let err = named.resolve("stbpt", false).unwrap_err();
    assert!(err.contains("stbpt") && err.contains("direct"), "{err}");
    let all = PassSet::parse("all").unwrap();
    let r = all.resolve("stbpt", false).unwrap();
    assert!(!r.direct && !r.indirect && r.albedo && r.motion);
    let r = all.resolve("path", true).unwrap();
    assert!(r.direct && r.indirect);
}
