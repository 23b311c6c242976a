//! The one place a technique is named.
//!
//! Each technique is one module plus one entry in [`TECHNIQUES`]: a [`Preset`] (usually a
//! `pub static` in the technique's own module) carrying its name, a one-line summary, its
//! settings type with their defaults, its [`Capabilities`] and how it is built (motion-blur
//! wrapping included). The command line's `--method` values, its flag checks, `bench
//! quality`'s effort scaling and the `--help` method list all come from here, so adding a
//! technique touches no file of the command line. As in pbrt-v4, where each integrator
//! parses its own parameters, the driver knows no names: settings travel as JSON
//! ([`resolve`]) and are checked by the technique's own serde type, so an unknown key or a
//! bad value is an error that names the valid keys.
//!
//! Presets such as `dept-spatial` are named default settings of one technique (`dept` with
//! its Gaussian filter), not separate types: `--method dept --set filter=...` and
//! `--method dept-spatial` reach the same code.

pub use crate::framework::technique::*;
use crate::kernels::elements::budget::PhotonCount;
use serde_json::Value;

/// Every technique, in the order `--help` lists them.
pub static TECHNIQUES: &[&dyn Technique] = &[
    &Listed(&crate::techniques::path::TECHNIQUE),
    &Listed(&crate::techniques::bdpt::TECHNIQUE),
    &Listed(&crate::techniques::dept::TECHNIQUE),
    &Listed(&crate::techniques::dept::SPATIAL),
    &Listed(&crate::techniques::dept::BILATERAL),
    &Listed(&crate::techniques::stbpt::TECHNIQUE),
    &Listed(&crate::techniques::spacetime_dept::TECHNIQUE),
    &Listed(&crate::techniques::pm_ic::TECHNIQUE),
    &Listed(&crate::techniques::ic_static_dynamic::TECHNIQUE),
    &Listed(&crate::techniques::ic_selective::TECHNIQUE),
    &Listed(&crate::techniques::spt::TECHNIQUE),
];

/// A technique as the list hands it out: itself, with its refusal of a capability it lacks
/// ([`LACKS_MAX_DEPTH`], [`LACKS_SHUTTER`]) completed by the techniques that have it. The
/// framework refuses (one rule, in [`Preset`]) but cannot name them: it sits below the
/// techniques. Every caller gets techniques from this list, so every refusal names them.
pub struct Listed(pub &'static dyn Technique);

impl Technique for Listed {
    fn name(&self) -> &'static str {
        self.0.name()
    }
    fn summary(&self) -> &'static str {
        self.0.summary()
    }
    fn capabilities(&self) -> Capabilities {
        self.0.capabilities()
    }
    fn quality(&self) -> &'static [QualityLevel] {
        self.0.quality()
    }
    fn defaults(&self) -> Value {
        self.0.defaults()
    }
    fn check(&self, settings: &Value) -> Result<Value, String> {
        self.0.check(settings).map_err(name_alternatives)
    }
    fn common(&self, settings: &Value) -> Result<CommonSettings, String> {
        self.0.common(settings).map_err(name_alternatives)
    }
    fn with_common(&self, settings: &Value, common: CommonSettings) -> Result<Value, String> {
        self.0
            .with_common(settings, common)
            .map_err(name_alternatives)
    }
    fn build(&self, settings: &Value, ctx: &BuildContext) -> Result<Renderer, String> {
        self.0.build(settings, ctx).map_err(name_alternatives)
    }
}

/// The technique `render` uses when no `--method` is given: `spacetime-dept`, the one the
/// equal-quality benchmarks (BENCHMARKS.md, "spacetime-dept against stbpt, each at its
/// defaults") show needing the least CPU at equal FLIP on every scene measured: the demo,
/// the peers' cornell-moving, a skinned character and the moving-camera `builtin:dolly`
/// (1.1–12.7× less than `stbpt`, which was the default before; 3.4× to over 18× less than
/// frame-by-frame `path` on the skinned character, cornell-moving and the dolly). Its
/// photons are pooled over a window of frames where the animation leaves the light
/// unchanged, and the eye pass reads caustics from them, so the demo renders without
/// fireflies through the glass (49 frames at 256² in 108 CPU seconds, stbpt 750; 99 with
/// the x86-64-v3 build: BENCHMARKS.md, "Issue 17: the default").
/// It is biased (element size, temporal pooling): its error flattens where `stbpt`'s keeps
/// falling (`--method stbpt` for an unbiased render that converges to `bdpt`). On models
/// lit only by the sky it is 2.4× faster than `path` at equal FLIP where nothing moves
/// (InterpolationTest's first frames); where something moves under the sky and indirect
/// light adds nothing to path tracing's noise, its path probe renders the frames as `path`
/// and says so in `run.json` (0.96–1.00× `path`'s CPU at 256² on BoxAnimated,
/// RiggedSimple, AnimatedMorphCube, 0.80–0.91× before: [`crate::kernels::probe`]).
/// One default rather than a per-scene rule: what a scene needs (reuse or not) is decided
/// by the technique from the animation while it renders (its change test cuts the
/// temporal window), not guessed by the driver before the scene is seen.
pub const DEFAULT_METHOD: &str = "spacetime-dept";

/// The technique called `name`, or an error listing the known ones.
pub fn find(name: &str) -> Result<&'static dyn Technique, String> {
    TECHNIQUES
        .iter()
        .copied()
        .find(|t| t.name() == name)
        .ok_or_else(|| format!("unknown method '{name}' (known: {})", names().join(", ")))
}

/// The names of every technique.
pub fn names() -> Vec<&'static str> {
    TECHNIQUES.iter().map(|t| t.name()).collect()
}

/// The names of the techniques with a capability.
pub fn names_where(f: impl Fn(&Capabilities) -> bool) -> Vec<&'static str> {
    TECHNIQUES
        .iter()
        .filter(|t| f(&t.capabilities()))
        .map(|t| t.name())
        .collect()
}

/// Appends to a framework refusal of a capability ([`LACKS_MAX_DEPTH`], [`LACKS_SHUTTER`])
/// the techniques that have it: only this list knows them.
fn name_alternatives(e: String) -> String {
    if e.contains("(it is for: ") {
        return e;
    }
    let having = if e.contains(LACKS_MAX_DEPTH) {
        names_where(|c| c.max_depth)
    } else if e.contains(LACKS_SHUTTER) {
        names_where(|c| c.motion_blur)
    } else {
        return e;
    };
    format!("{e} (it is for: {})", having.join(", "))
}

/// `--help` text: one line per technique.
pub fn help_list() -> String {
    TECHNIQUES
        .iter()
        .map(|t| format!("`{}`: {}", t.name(), t.summary()))
        .collect::<Vec<_>>()
        .join("; ")
}

/// The settings a quality level gives `technique` (its defaults with the level's effort
/// settings), with the level; `quality`: the `--quality` given (`None`: the default
/// quality, which leaves the defaults where the technique has no table, or no undenoised
/// entry when `denoise` is false); `pixels`: the image's pixel count, which picks the
/// level's entry measured nearest it ([`QualityLevel::pixels`]; `None`: the shared 256²).
/// An explicit level that is not measured is an error that says what is.
pub fn quality_settings(
    technique: &dyn Technique,
    quality: Option<&str>,
    denoise: bool,
    pixels: Option<u64>,
) -> Result<Option<(Value, QualityLevel)>, String> {
    let name = quality.unwrap_or(DEFAULT_QUALITY);
    if !QUALITIES.contains(&name) {
        return Err(format!(
            "--quality {name}: the levels are {}",
            QUALITIES.join(", ")
        ));
    }
    let with_table = || names_where_quality().join(", ");
    let pixels = pixels.unwrap_or(u64::from(MEASURED_PIXELS));
    let Some(level) = QualityLevel::nearest(technique.quality(), name, pixels) else {
        return match quality {
            None => Ok(None),
            Some(_) => Err(format!(
                "--quality {name}: --method {} has no measured quality table (those with one: {}); set its effort with --spp, --photons or --set",
                technique.name(),
                with_table()
            )),
        };
    };
    let pairs = if denoise {
        level.denoised
    } else {
        match (level.undenoised, quality) {
            (Some(p), _) => p,
            (None, None) => return Ok(None),
            (None, Some(_)) => {
                return Err(format!(
                    "--quality {name} of --method {} is measured for denoised renders only; without --no-denoise it applies, or set the effort with --spp, --photons or --set",
                    technique.name()
                ));
            }
        }
    };
    let mut s = technique.defaults();
    for (k, v) in pairs {
        set_key(&mut s, k, parse_value(v))
            .map_err(|e| format!("quality table of {} ({name}): {e}", technique.name()))?;
    }
    let s = technique
        .check(&s)
        .map_err(|e| format!("quality table of {} ({name}): {e}", technique.name()))?;
    Ok(Some((s, *level)))
}

/// The techniques with a quality table.
pub fn names_where_quality() -> Vec<&'static str> {
    TECHNIQUES
        .iter()
        .filter(|t| !t.quality().is_empty())
        .map(|t| t.name())
        .collect()
}

/// Applies `--photons N|auto` to photon settings: a count sets `photons` and clears
/// `auto` where the method has one; `auto` sets the stopping rule's defaults (an error
/// naming the valid keys for a method without one).
pub fn set_photons(settings: &mut Value, count: &PhotonCount) -> Result<(), String> {
    match count {
        PhotonCount::Fixed(n) => {
            set_key(settings, "photons", Value::from(*n))?;
            // Only the methods with a stopping rule have `auto` to clear (`spt`'s pool
            // is a fixed count).
            if find_key(settings, "auto").is_some() {
                set_key(settings, "auto", Value::Null)?;
            }
            Ok(())
        }
        PhotonCount::Auto(a) => set_key(
            settings,
            "auto",
            serde_json::to_value(a).map_err(|e| e.to_string())?,
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_technique_has_a_unique_name_and_checks_its_own_defaults() {
        let mut seen = std::collections::HashSet::new();
        for t in TECHNIQUES {
            assert!(seen.insert(t.name()), "duplicate {}", t.name());
            let d = t.defaults();
            assert_eq!(t.check(&d).unwrap(), d, "{}", t.name());
            let e = t.capabilities().effort;
            assert!(
                find_key(&d, e.key).is_some(),
                "{}: effort key {}",
                t.name(),
                e.key
            );
        }
    }

    /// Every quality table names the known levels in order, sets keys its technique has
    /// (the settings check), and its error falls as the level rises.
    #[test]
    fn quality_tables_are_well_formed() {
        for t in TECHNIQUES {
            let q = t.quality();
            if q.is_empty() {
                assert!(quality_settings(*t, None, true, None).unwrap().is_none());
                assert!(quality_settings(*t, Some("final"), true, None).is_err());
                continue;
            }
            // Every resolution measured has the whole table, each entry once.
            let mut resolutions: Vec<u32> = q.iter().map(|l| l.pixels).collect();
            resolutions.dedup();
            assert!(resolutions.contains(&MEASURED_PIXELS), "{}", t.name());
            for px in &resolutions {
                let at: Vec<&QualityLevel> = q.iter().filter(|l| l.pixels == *px).collect();
                let names: Vec<&str> = at.iter().map(|l| l.name).collect();
                assert_eq!(names, QUALITIES, "{} at {px} pixels", t.name());
                assert!(
                    at.windows(2).all(|w| w[1].flip < w[0].flip),
                    "{}: FLIP not falling at {px} pixels",
                    t.name()
                );
            }
            for l in q {
                assert!(["high", "fast"].contains(&l.denoiser), "{}", t.name());
                for denoise in [true, false] {
                    match quality_settings(*t, Some(l.name), denoise, Some(u64::from(l.pixels))) {
                        Ok(Some((s, got))) => {
                            assert_eq!(got, *l);
                            let pairs = if denoise {
                                l.denoised
                            } else {
                                l.undenoised.unwrap()
                            };
                            for (k, v) in pairs {
                                assert_eq!(get_key(&s, k), Some(&parse_value(v)), "{}", t.name());
                            }
                        }
                        Ok(None) => panic!("{}: an explicit level gave nothing", t.name()),
                        Err(e) => assert!(!denoise && l.undenoised.is_none(), "{e}"),
                    }
                }
            }
        }
        assert!(quality_settings(TECHNIQUES[0], Some("ultra"), true, None).is_err());
    }

    /// A level measured at several resolutions gives each render the entry nearest its
    /// pixel count by ratio: 1080p (2.07 M pixels) is nearer 512² (0.26 M) than 256².
    #[test]
    fn quality_entry_nearest_the_pixel_count() {
        const TABLE: &[QualityLevel] = &[
            QualityLevel::denoised("preview", 0.08, &[("spp", "4")]),
            QualityLevel::denoised("preview", 0.08, &[("spp", "2")]).at(512, 512),
        ];
        let pick = |px: u64| {
            QualityLevel::nearest(TABLE, "preview", px)
                .unwrap()
                .denoised[0]
                .1
        };
        assert_eq!(pick(256 * 256), "4");
        assert_eq!(pick(128 * 128), "4");
        assert_eq!(pick(360 * 360), "4"); // 362² is the geometric middle
        assert_eq!(pick(364 * 364), "2");
        assert_eq!(pick(1920 * 1080), "2");
        // The registry's own table: the default route at 1080p takes its 512² entry.
        let st = find("spacetime-dept").unwrap();
        let (_, at_1080p) = quality_settings(st, None, true, Some(1920 * 1080))
            .unwrap()
            .unwrap();
        assert_eq!(at_1080p.pixels, 512 * 512);
        let (_, at_256) = quality_settings(st, None, true, None).unwrap().unwrap();
        assert_eq!(at_256.pixels, MEASURED_PIXELS);
    }

    /// `--set spp=0` and `--set max_depth=0` rendered black images without a word; every
    /// technique with such a key now refuses them, naming the key, and keeps 1.
    #[test]
    fn zero_samples_or_depth_are_refused_for_every_technique() {
        for t in TECHNIQUES {
            for key in ["spp", "max_depth"] {
                if find_key(&t.defaults(), key).is_none()
                    || (key == "max_depth" && !t.capabilities().max_depth)
                {
                    continue;
                }
                let e = resolve(*t, None, &[(key.into(), Value::from(0))]).unwrap_err();
                assert!(e.contains(&format!("{key} = 0")), "{}: {e}", t.name());
                resolve(*t, None, &[(key.into(), Value::from(1))]).unwrap();
            }
        }
    }

    /// Every technique has the common block, reached by type: `with_common` changes
    /// exactly the keys `spp`, `seed` and `max_depth` (wherever the technique keeps them:
    /// `bdpt.spp` in stbpt's settings) and nothing else; a depth is refused by the
    /// techniques that do not implement one, naming those that do.
    #[test]
    fn every_technique_has_the_common_block() {
        for t in TECHNIQUES {
            let d = t.defaults();
            let c = t.common(&d).unwrap();
            for (key, v) in [("spp", Value::from(c.spp)), ("seed", Value::from(c.seed))] {
                assert_eq!(get_key(&d, key), Some(&v), "{}: {key}", t.name());
            }
            assert_eq!(get_key(&d, "max_depth"), Some(&Value::Null), "{}", t.name());
            let new = CommonSettings {
                spp: c.spp + 3,
                seed: 77,
                max_depth: None,
            };
            let s = t.with_common(&d, new).unwrap();
            assert_eq!(t.common(&s).unwrap(), new, "{}", t.name());
            let mut expect = d.clone();
            set_key(&mut expect, "spp", Value::from(c.spp + 3)).unwrap();
            set_key(&mut expect, "seed", Value::from(77)).unwrap();
            assert_eq!(s, expect, "{}: only the common keys change", t.name());
            let deep = CommonSettings {
                max_depth: Some(4),
                ..new
            };
            match t.with_common(&d, deep) {
                Ok(s) => {
                    assert!(t.capabilities().max_depth, "{}", t.name());
                    assert_eq!(get_key(&s, "max_depth"), Some(&Value::from(4)));
                }
                Err(e) => {
                    assert!(!t.capabilities().max_depth, "{}: {e}", t.name());
                    assert!(e.contains("max_depth = 4") && e.contains("path"), "{e}");
                    let e = resolve(*t, None, &[("max_depth".into(), Value::from(4))]);
                    assert!(e.is_err(), "{}: --set max_depth=4 accepted", t.name());
                }
            }
        }
    }

    #[test]
    fn set_finds_nested_keys_and_rejects_unknown_ones() {
        let t = find("stbpt").unwrap();
        let s = resolve(
            t,
            None,
            &[
                ("window".into(), parse_value("6")),
                ("spp".into(), parse_value("3")),
                ("bdpt.mis".into(), parse_value("balance")),
            ],
        )
        .unwrap();
        assert_eq!(s["window"], 6);
        assert_eq!(s["bdpt"]["spp"], 3);
        let e = resolve(t, None, &[("windw".into(), parse_value("6"))]).unwrap_err();
        assert!(
            e.contains("unknown setting 'windw'") && e.contains("film_budget_mb"),
            "{e}"
        );
        let e = resolve(t, None, &[("window".into(), parse_value("six"))]).unwrap_err();
        assert!(e.contains("--set window=\"six\""), "{e}");
        let e = resolve(t, Some(&serde_json::json!({"bdpt": {"sp": 1}})), &[]).unwrap_err();
        assert!(e.contains("unknown field `sp`"), "{e}");
    }

    #[test]
    fn presets_are_settings_of_one_technique() {
        let spatial = find("dept-spatial").unwrap().defaults();
        let plain = find("dept").unwrap();
        let s = resolve(plain, None, &[("filter".into(), spatial["filter"].clone())]).unwrap();
        assert_eq!(s, spatial);
    }

    /// A capability a technique lacks is refused by the framework and, through the list,
    /// the refusal names every technique that has it (from the capabilities, so it stays
    /// right when a technique gains one).
    #[test]
    fn a_refused_capability_names_the_techniques_that_have_it() {
        let depth = names_where(|c| c.max_depth).join(", ");
        let blur = names_where(|c| c.motion_blur).join(", ");
        for t in TECHNIQUES {
            let caps = t.capabilities();
            let sets = [("max_depth".to_string(), Value::from(3))];
            match resolve(*t, None, &sets) {
                Ok(_) => assert!(caps.max_depth, "{}", t.name()),
                Err(e) => {
                    assert!(!caps.max_depth, "{}: {e}", t.name());
                    assert!(e.contains(LACKS_MAX_DEPTH) && e.contains(&depth), "{e}");
                }
            }
            let ctx = BuildContext { shutter: 0.5 };
            match t.build(&t.defaults(), &ctx) {
                Ok(_) => assert!(caps.motion_blur, "{}", t.name()),
                Err(e) => {
                    assert!(!caps.motion_blur, "{}: {e}", t.name());
                    assert!(e.contains(LACKS_SHUTTER) && e.contains(&blur), "{e}");
                }
            }
        }
    }
}
