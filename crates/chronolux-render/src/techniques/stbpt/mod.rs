//! Spatio-temporal bidirectional path tracing (Havran, Damez, Myszkowski, Seidel, "An
//! efficient spatio-temporal architecture for animation rendering", EGSR 2003): every
//! bidirectional sample made for a pixel of frame f also serves the frames g of the
//! centred window [f − K, f + K], at the pixel through which its first eye vertex is seen
//! in g.
//!
//! # Per sample (generated once, in frame f)
//!
//! A BDPT sample as [`crate::kernels::bdpt`] makes it (camera subpath, light subpath, every
//! strategy (s, t) with MIS), from three streams of its own: camera, light and connection
//! numbers. Separate streams let a sample be re-traced in another frame with a camera
//! subpath of a different length without the light subpath or the light samples reusing
//! numbers the camera subpath consumed.
//!
//! **Sample streams across frames.** Each stream is one Owen-scrambled Sobol sequence per
//! pixel for a block of up to 1024 frames (fewer above 64 spp, so that the points stay
//! among the sequence's first 2^16), keyed by (seed, pixel, block); sample i of frame f is
//! its point (f / n mod block)·spp + i (n: `interleave`; [`stream_index`]). The frames generating
//! a pixel thus take consecutive runs of points of one sequence, and the samples that the
//! frames of a window land in a static pixel are stratified together, where independent
//! per-frame sequences would land the first points of 2K + 1 unrelated scrambles (as many
//! independent random samples). Each sample is still uniformly distributed on its own, so
//! nothing changes in expectation. Measured (BENCHMARKS.md, "Issue 17: sample streams
//! across frames"): FLIP −7 % and relMSE −45 % on cornell-moving at 1 spp (K = 2, 4),
//! FLIP −3 to −9 % on the demo.
//!
//! Recorded: the first eye vertex x1 (a surface point: geometry id, triangle and
//! barycentrics through the instance that carries it — never a pixel), every ray the two
//! subpaths traced, and the **shading split** (item 4): the t ≥ 2 contributions are
//! written `f(x1, wo, wi_k) ⊙ R_k` with `R_k` holding everything but x1's BSDF value for
//! the view direction `wo` — the NEE and light-vertex connections at x1 (t = 2, `wi_k`
//! towards the light point), and each strategy with t ≥ 3 (they all share x1's sampled
//! continuation `wi`: `R = c ⊘ f(wo_f, wi)`, i.e. the incident radiance estimate times
//! |cos|/pdf and its MIS weight). x1's own emission (s = 0, t = 2) is kept as its MIS
//! weight, the emitted radiance being re-evaluated towards the new view. Directions are
//! kept in world space: reuse happens only while x1's surface does not move (its object,
//! or on a deforming mesh its triangle), when x1's shading frame is the same in f and g,
//! so world and local directions are equivalent.
//!
//! # Reuse in frame g
//!
//! 1. **Landing.** x1 in g (same triangle and barycentrics on g's geometry: motion
//!    compensated) is projected into g's camera; it lands in g iff it is on screen, faces
//!    g's camera from the same side as f's, and nothing in g occludes it. Samples whose
//!    camera ray escaped land where their direction projects in g. A sample that does not
//!    land does not serve g's camera part (it still serves g's light tracing, below).
//! 2. **Reuse** (the view-dependent part only) when everything the split depends on is
//!    reproduced in g: x1's surface is the same in f and g (as every scene comparison
//!    here: from the exact [`FrameDelta`]s of f and the window frames) — its instance has
//!    the same placement and, on a skinned or morphed mesh, x1's own triangle has the
//!    same vertex data in both frames ([`FrameDelta::triangle_changed`]: the still part of
//!    a deforming mesh, e.g. the vertices bound to joints that do not move, is reused as
//!    static geometry is, and the mesh's moving part is answered per frame by the
//!    multi-frame structure like any dynamic geometry) — the sample continued from x1
//!    by a non-delta lobe, x1 is not near-specular
//!    ([`Bsdf::near_specular`]: GGX α < 0.1) while the camera moved (the continuation,
//!    sampled for f's view, would not cover g's lobe), materials and lights are the same,
//!    and every segment the subpaths sampled beyond x1 — camera segments after x1, all
//!    light segments, escape rays included — gives the same hit in g as in f according to [`MultiFrameAccel::intersect_window`] (the
//!    module's "Use for sample reuse"). Shadow rays of the connections are not a validity
//!    condition: [`MultiFrameAccel::occluded_window`] answers them for every frame at
//!    generation, and an occluded connection contributes 0 in that frame. The value in g
//!    is `Le(x1 → wo_g)·w_e + Σ_k V_k(g) f(x1, wo_g, wi_k) ⊙ R_k`: only x1's BSDF and
//!    emission are re-evaluated.
//!    **Partial reuse** when only the light subpath is invalid in g (x1 and every camera
//!    segment reproduced, same lights and materials): the strategies whose light vertices
//!    are all reproduced in g — s ≤ p, the light subpath's valid prefix (below), and
//!    always those without light-subpath vertices (s ≤ 1: emission, NEE, camera paths
//!    hitting a light) — are reused as above, and the others are recomputed in g's scene
//!    by connecting f's camera subpath (which is g's walk too) to the light subpath
//!    regenerated in g, split at x1 the same way. A strategy (s, t), its contribution and
//!    its MIS weight, depends only on light vertices 0..s and camera vertices 0..t, and
//!    each strategy's weighted contribution is an unbiased estimate of its share on its
//!    own, so mixing f's s ≤ p terms with g's s > p terms is unbiased.
//!
//!    **Valid prefix of a light subpath.** Vertex i of the light subpath is reproduced
//!    in g (the same vertex) when g's lights and materials are f's and the rays that made
//!    vertices 1..=i give f's hits in g (the multi-frame masks): the first p vertices.
//!    A light subpath invalid in g is regenerated in g from the same light stream; its
//!    first p − 1 rays are f's rays and are answered with f's hits, without a traversal,
//!    so the regenerated subpath is exactly the one a full re-trace gives. With g's camera
//!    equal to f's, the light-tracing splats (t = 1) with s ≤ p are f's (where their
//!    shadow rays, answered for the window at generation, are unoccluded in g); only
//!    those with s > p are made in g.
//! 3. **Re-trace** otherwise: a fresh BDPT evaluation in g's scene, of the same streams,
//!    for a camera ray through the raster position where x1 landed. A sample invalid for
//!    g never contributes a stale value; re-tracing (instead of dropping) keeps the
//!    samples landing in a pixel independent of where geometry changed, so changed regions
//!    are not under-sampled relative to static ones.
//!    **Valid prefix of a camera subpath.** With g's camera equal to f's and x1 not moved,
//!    the re-trace starts from f's raster position with f's camera stream, so the walk in
//!    g repeats f's vertices as long as their rays give f's hits in g (the multi-frame
//!    masks, same materials): camera vertices 0..=c. Those c rays are answered with f's
//!    hits, without a traversal, and every strategy (s, t) made of reproduced vertices
//!    only (t ≤ c + 1, s ≤ the light subpath's valid prefix) is f's value where its shadow
//!    ray is unoccluded in g; only the others are evaluated in g (their connection
//!    numbers kept aligned by [`crate::kernels::bdpt::skip_connect`]). The result is the full
//!    re-trace's value (checked against it under debug assertions). On cornell-moving
//!    (static camera, a sliding cube; N = 2, K = 8, 256²) 61 % of the re-traces keep a
//!    prefix, c = 1 for 47 % of those and 2–4 for 50 %; 39 % have x1 on the cube and keep
//!    nothing. Ray queries there −10 % closest-hit, −14 % shadow (BENCHMARKS.md, "Issue
//!    17: stbpt re-traces from the camera subpath's valid prefix").
//! 4. **Light tracing** (t = 1): every light subpath of the window serves g: reused when
//!    its segments are reproduced in g and the lights are the same, otherwise re-generated
//!    in g from the same light stream; its vertices are connected to g's camera and
//!    splatted. When g's camera is f's and the light subpath is reused, the connections
//!    are the same too: f's splats are reused, each where its shadow ray (answered for
//!    the window at generation) is unoccluded in g. Frame g's splats are scaled by
//!    1 / (spp × frames of g's window).
//!
//! # Cost
//!
//! Both subpaths are traced through the window structure itself
//! ([`MultiFrameAccel::intersect_window`], whose answer for f equals f's own query), so each
//! segment's validity over the window costs no second traversal. x1's landing visibility
//! is one [`MultiFrameAccel::occluded_window`] query for every frame in which x1 and the
//! eye are where they were in f (static object, static camera position), one ray per
//! frame otherwise.
//!
//! Pixel value of g: Σ values / Σ landed samples per pixel ([`WindowFilm`]), plus the
//! scaled splats.
//!
//! # Bias
//!
//! Each landed sample is an unbiased estimate of the radiance through the raster position
//! it landed at (re-traced ones trivially; reused ones because f's continuation density
//! is the density the sample was drawn with — `f(wo_g, wi)/pdf_f(wi)` is an ordinary
//! importance-sampling weight wherever `pdf_f > 0`, which holds for the non-delta,
//! non-near-specular lobes reuse is restricted to). The pixel value is the mean over the
//! samples that landed, so it estimates the radiance averaged over the pixel with the
//! *landing density*. From one source frame f, that density is f's uniform raster density
//! moved by a smooth map (1 / its Jacobian) on the part of g's pixel that f sees, and
//! zero on the rest (off f's screen, hidden in f, background f sees covered). The mean
//! is then the mean over the part f sees: on the dolly, frame 0's left pixel column
//! shows the room's open edge against the black background; frames 1 and 2, further
//! right, see the wall part of it but not the background part, and the column came out
//! +65 % (its 8×8 blocks +3 to +7 %, t = 7.2: test
//! `stbpt_agrees_with_bdpt_under_a_moving_camera`). Escaped rays made it worse: landed by
//! direction, one re-traced where g's ray meets the wall doubled the density there (the
//! wall's own landings from f serve the same points). So:
//!
//! - a pixel of g takes landings from f only if f sees its whole footprint, tested at its
//!   four corners and its centre (where g sees a surface: that point, moved with its
//!   object into f, on f's screen, facing f from g's side and unoccluded from f's eye;
//!   where g sees the background: the same direction escaping from f's eye), computed per
//!   generated frame for every window frame g whose camera or geometry differs from f's
//!   (about two test points per pixel; with a moving camera one closest-hit and one
//!   shadow query per point and window frame; with f's camera one window query per point
//!   answers every such frame, and only points on a moved surface need a shadow query;
//!   a static pair costs nothing);
//! - an escaped ray lands in g only where g's camera ray escapes too.
//!
//! Every point g sees then has at most one landing preimage in f, and on a pixel that
//! passes, the landing density from each f is the smooth one: the estimate is unbiased
//! up to that density's variation across the pixel (second order in the pixel size,
//! where the radiance varies linearly) and up to what the five test points miss: a part
//! of the footprint unseen by f that contains none of them (thinner than half the pixel's
//! diagonal). For such a pixel the mean is over the seen part: the error is at most its
//! unseen area fraction times the radiance difference between the two parts. The cost is
//! the landings dropped, on pixels at silhouettes and on the image border where the
//! camera trucks or dollies, which are served by fewer frames (noisier, not darker).
//!
//! **MIS weights in another frame.** The weights of a reused sample are computed in f
//! for f's camera, and g's light-tracing splats (t = 1) are weighted for g's camera.
//! The strategies t ≥ 2 and t = 1 partition each path's contribution in g when the
//! t ≥ 2 weights are g's too: the weights BDPT would give the same path seen from g's
//! camera (any partition of unity keeps each landing unbiased; the landed samples stand
//! for g's camera samples in g's pixel, as the pixel mean over them does above). Only
//! three densities in a weight's ratios involve the camera x0
//! ([`crate::kernels::bdpt::ViewSplit`]): x1's density from the camera p_cam(x1) (in light
//! tracing's ratio only, t′ = 1: every other strategy samples x1 from the camera too),
//! and the densities at x1 that depend on the direction to x0: for t ≥ 3 the
//! continuation's p(x1 → x2), for t = 2 the reverse density towards the light vertex
//! connected to. So each entry keeps its weight split by those terms
//! ([`crate::kernels::bdpt::view_split`]) and g rescales them with the ratios of the three
//! densities, p_cam,f(x1) / p_cam,g(x1) and one BSDF density ratio
//! ([`crate::kernels::bdpt::ViewSplit::reweight`]); the strategies recomputed for partial reuse
//! likewise. `tests/it/bdpt.rs` checks that this equals the weight computed from scratch
//! with g's camera vertex, for every strategy of a thousand paths on the dolly, and fails
//! without either view factor. Without the re-weighting the moving-camera tests fail,
//! +4 % on the dolly's red wall (t = 6.3). Before, a moving camera turned light tracing
//! off for the sequence, which left the metal sphere's reflection of the lamp on the
//! dolly's ceiling to camera paths, as fireflies: relMSE at 4 spp, frames 8–15, 0.0256 →
//! 0.0065 with it, for 38 % more CPU (BENCHMARKS.md, "stbpt under a moving camera: light
//! tracing kept").
//!
//! # Motion blur (`shutter` > 0)
//!
//! Every landing also records where the point it shows is seen one frame before and one
//! after (the sample's x1 moved with its object into those frames and projected by their
//! cameras, visible or not; an escaped ray's direction for the background), and its value
//! there when that landing shows the same point (own frame or reuse; a re-traced landing
//! may show another point, so its radiance is not interpolated). Per pixel of frame g the
//! films keep the means of these over the landed samples; when g is finished, each pixel's
//! value is spread over the pixels its trajectory crosses during the shutter
//! ([`splat_trajectory`], 2D DDA, weight ∝ time ∝ length at constant speed), positions and
//! radiance linear in time between frames. **Deviation from a per-sample splat:** the
//! trajectory is splatted per pixel of the reconstructed frame, not per sample, because
//! a landed sample's share of its pixel (1 / samples landed there) is known only when the
//! window is complete; splatting each sample as it lands would weight pixels by landing
//! density (which doubles where the scene's motion brings samples of two frames onto the
//! same point). Consequences: a pixel showing two differently moving surfaces spreads its
//! mean along their mean trajectory; only points visible at the frame instant are spread,
//! so background revealed during the shutter is missing from the blur (as in the paper);
//! light-tracing splats are not blurred. Needs K ≥ 1 (the neighbouring frames); at the
//! ends of the render list the trajectory is extrapolated from the frame on the other
//! side. Test: a quad moving at constant speed against the analytic box⊗box blur
//! (`tests/it/blur.rs`).
//!
//! # Choosing K
//!
//! Each generated frame f has its own half-width K_f ≤ `window` (the cap). After f's
//! samples are made, [`adapt::assess`] compares, per distance d = |g − f| served, what
//! reuse gave with what serving cost beyond re-tracing, both per generated sample and
//! counted (not timed, so images do not depend on threads or load): value = 0.7 × reused
//! landings (a reused sample is worth ≈ 0.7 of a fresh one); cost = the ray queries spent
//! in those frames other than the re-traces' (landing rays, regenerated light subpaths,
//! light tracing, partially recomputed strategies, the coverage test of "Bias") over those
//! of f's own samples (≈ a BDPT sample each), + 0.05 per landing (BSDF re-evaluation,
//! film writes). A re-traced landing is a fresh sample at a fresh sample's price and
//! counts neither way. K is the largest distance such that every distance up to it paid.
//! When distance 1 does not pay, K = 0: the samples serve only their own frame, i.e. the
//! effort is spent as frame-by-frame `bdpt` spends it, or as `path` spends it when the
//! frame uses the path strategies (next section). With motion blur K ≥ 1 (the trajectories need the
//! neighbouring frames). The decision and its statistics are reported per frame
//! (`reuse_decision` in `run.json`). A frame's splats are scaled by the number of
//! generated frames that served it, and a frame is output once every frame that may
//! serve it (within the cap) is generated.
//!
//! **Grid frames: the same decisions in any farm segment.** The measurements are made on
//! the **grid frames**, the frames whose index is a multiple of [`adapt::GRID`] (4): a
//! grid frame is generated at the cap K with all strategies measuring at the pilot pixels
//! (next section; a pilot frame when `path_strategies` is set), over every frame within
//! the cap of it whether it is in the render list or not (its landings in frames outside
//! the list are counted, not kept), and its measurement chooses K and the strategies of
//! the frames up to the next grid frame. So every decision is a function of one grid
//! frame's index and the scene, never of what a process generated before: a farm segment
//! (its own process, its own render list) whose frames follow a grid frame it does not
//! render generates that grid frame first, and renders the frames a single run renders,
//! bit for bit (test `stbpt_segments_render_the_frames_of_a_single_run`). The price: one
//! frame in four is generated at the cap K with all strategies even where the measurement
//! says otherwise (where reuse does not pay its landings are re-traces, i.e. fresh samples
//! moved to its neighbours; where the path strategies win it costs a BDPT frame instead
//! of a path frame); a segment may generate one grid frame before its own frames only to
//! measure (at most the cap K + [`adapt::GRID`] − 1 frames before its first frame), and a
//! clip's end grid frame lands in up to K frames past the end only to measure. Per frame,
//! `reuse_decision` and `strategy_decision` say `grid` for a frame made as its grid frame
//! chose (their statistics are of the frame's own window, which a segment may cut).
//!
//! What the counts leave out: the extra cost of a window query over a single-frame one
//! (dynamic instances are answered per frame, so it grows with K on deforming meshes) is
//! charged to f's own samples, i.e. counted as BDPT cost; the value of the light-tracing
//! splats a frame receives from regenerated light subpaths is not counted.
//!
//! # BDPT or the path strategies
//!
//! **Why BDPT loses to `path` on some scenes.** Measured on the skinned RiggedSimple in the
//! Cornell stage (64×64, frames 0–7, 8 spp, `--threads 1`; CPU s from `bench quality`,
//! ray queries from `run.json`; `bench-results/2026-12-02-stbpt2/cost-calibration/`): a
//! BDPT sample costs 4.2× a `path` sample (3.33 against 0.79 CPU s). Its camera walk and
//! light samples (s ≤ 1) are `path`'s own work (0.98 M closest-hit, 0.65 M shadow
//! queries); on top come the light subpaths (+0.92 M closest-hit queries, 94 % of the
//! camera walks') and +2.55 M connections, about 30 % of them light tracing (t = 1) and the
//! rest s ≥ 2, t ≥ 2, each with its BSDF evaluations and an MIS weight over the whole path
//! (fitted: 0.95 µs per connection against 0.25 µs per closest-hit query, see
//! [`strategies::SHADOW_QUERY_COST`]): the connections are three quarters of BDPT's time
//! there. What they buy is small: the strategies s ≥ 2 carry about a third of the image's
//! light (`contribution_shares` in `run.json`: 66 % s ≤ 1, 10 % connections, 24 % light
//! tracing, much as on the demo), but it is light the path strategies also sample well,
//! so MIS only moves weight between strategies: measured per sample on the same camera
//! subpaths (the pilot below), BDPT's relative variance is 0.29–0.33 against 0.5–0.7 for
//! the path strategies, 1.7–2.2× lower for 4× the cost. The room is diffuse and lit by a
//! large ceiling light that light sampling finds from almost every camera vertex. Where a
//! glass sphere focuses the light (the demo, `builtin:caustic`), camera paths find the
//! caustic only by hitting the lamp through the glass: the path strategies' variance is
//! 10–90× BDPT's (importance-sampled, below; 1.3–6× as sampled from their own few
//! samples, which rarely meet those paths) and BDPT wins.
//!
//! **The path strategies** ([`BdptSettings::path_strategies`]): the same camera subpath,
//! only the strategies s = 0 (the walk hits an emitter) and s = 1 (a light sample at each
//! camera vertex), MIS (power heuristic) over those two only, no light subpath, no light
//! tracing: `path`'s estimator written with BDPT's vertices, so everything above
//! (landing, the shading split at x1, validity, partial reuse, re-traces, K) applies
//! unchanged; with no light subpath, a sample is valid in g wherever its camera segments
//! are and g's lights and materials are f's. Unbiased for the same reasons as BDPT without
//! light tracing (its weights sum to one over the strategies it keeps, which all sample
//! x1 from the camera: also with a moving camera).
//!
//! **The decision**, per grid frame, from counts and sample values of the frame's own
//! samples ([`strategies::decide`]): a sample made with all strategies also evaluates the
//! value the path strategies give on the same camera subpath and the same light samples (s
//! ≤ 1 contributions re-weighted by [`crate::kernels::bdpt::mis_weight`] among themselves: no ray),
//! and counts the cost of both parts (closest-hit queries +
//! [`strategies::SHADOW_QUERY_COST`] per shadow query, fitted to CPU time), at a quarter of
//! the pixels ([`strategies::pilot_pixel`]: horizontal pairs, spread over the image), on
//! the grid frames (above), which use all strategies everywhere: a **pilot frame** (all
//! strategies and the measurements at those pixels, the path strategies elsewhere, a
//! quarter of a BDPT frame's extra work) would be cheaper where the path strategies win,
//! but cost the demo up to 30 % at equal FLIP (its path samples spread caustic fireflies
//! over the window); grid frames are pilot frames only when `path_strategies` is set.
//! Variances are of the luminance, relative (per pixel divided by the local mean², floored
//! at 0.1 of the frame mean), per sample; BDPT's includes its light-tracing splats (Σ c² /
//! spp per pixel). The path strategies' variance from their own few samples would miss
//! exactly what makes them lose: rare high-valued paths (caustics seen through a diffuse
//! surface), which 1–4 samples per pixel seldom meet. So their **diagonal** second moment
//! (Σ over strategies of w'² f² / p_{s'}) is importance-sampled from every BDPT
//! contribution (light tracing included), with the density ratios p_{s'} / p_u of the BDPT
//! path ([`crate::kernels::bdpt::strategy_ratios`]), replacing the sampled diagonal terms; the cross
//! terms between path lengths of one camera walk stay as sampled. BDPT's contributions from
//! paths no path strategy can make (delta lights behind specular surfaces) count as
//! `unreachable_share`: above [`strategies::UNREACHABLE_MAX`], BDPT is kept whatever the
//! variances. The frames after a grid frame use the path strategies iff [`strategies::SWITCH_MARGIN`]
//! (1.5) × variance_path × cost_path < variance_bdpt × cost_bdpt, else all strategies (the
//! margin because the few samples per pixel miss heavy tails: on the dolly the ratio
//! reached 1.1 where all strategies were better), for the frames up to the next grid
//! frame (which measures again). The figures are in `run.json` per
//! frame (`strategy_decision`, beside `reuse_decision`). The comparison is of the frame's
//! own samples: it assumes a landing in another frame is worth the same share of a fresh
//! sample with either strategy set, and it leaves the pilot's own work (the re-weighting
//! and density ratios at a quarter of the pixels) in BDPT's cost. Relative variance weighs
//! pixels by 1 / (local mean)², a stand-in for FLIP's perceptual error, not FLIP itself.
//!
//! **Samples of both kinds.** A frame g may be served by samples with light tracing (all
//! strategies, static camera) and without it (path strategies), from different generated
//! frames or within a pilot frame: the first estimate the radiance minus its
//! light-tracing share at their landings, the others all of it. Each landing of a sample
//! with light tracing is counted per pixel (in the splat film's weights); the splats,
//! normalised by the light subpaths that made them (spp × the summed share ρ of samples
//! with light tracing of the serving frames), are weighted per pixel by the share
//! n_lt / n of the landings there that had light tracing, so the pixel's expectation is
//! (n_lt (μ − μ_lt) + (n − n_lt) μ) / n + (n_lt / n) μ_lt = μ (test
//! `stbpt_frames_of_both_strategy_sets_agree_with_bdpt`).
//!
//! [`BdptSettings::path_strategies`]: crate::kernels::bdpt::BdptSettings::path_strategies
//!
//! # Interleaved generation (`interleave` = n > 1)
//!
//! Each frame generates its `spp` samples per pixel at one pixel in n
//! ([`generated_at`]: a 4×4 Bayer matrix over horizontal pixel pairs, frame f taking the
//! (f mod n)-th of n rank ranges, so any n consecutive frames generate every pixel once),
//! and the window's landings serve the other pixels. It is the effort below one sample
//! per pixel and frame (measured in BENCHMARKS.md, "Issue 17: interleaved generation").
//!
//! **Bias.** Each landing estimates the radiance at the raster position it landed at,
//! as above. Where nothing moves, a pixel's landings are the samples of the frames that
//! generate it, uniform over the pixel. Where the scene or the camera moves, the landings
//! in g's pixel are those of f's generating pixels moved into it: the landing density is
//! f's lattice of generating pixels moved, uneven within the pixel, so the pixel mean
//! weighs parts of the pixel unevenly. That is a change of pixel filter, an error of at
//! most the radiance variation within the pixel (first order in the pixel size, where the
//! smooth density of the full generation leaves a second-order one); 8×8 block tests do
//! not resolve it (`stbpt_interleaved_generation_agrees_with_bdpt`).
//!
//! **Fill.** A pixel no landing reached (K = 0, a disocclusion, landings dropped by the
//! coverage test under a moving camera) gets `spp` samples of its own frame with the path
//! strategies (`Stbpt::fill`, a stream keyed by (seed, frame, pixel), the count in
//! `reuse.filled` in `run.json`): the pixel's value is then a mean of unbiased estimates
//! whether or not landings reached it. Those samples estimate all of the pixel's light, so
//! the light-tracing splats weigh 0 there ("Samples of both kinds"). With motion blur a
//! filled pixel has no trajectory and is spread as a still one.
//!
//! # Memory
//!
//! Samples are not stored: each is made, landed in every frame of its window and
//! dropped. What stays is the open frames' films (value, square, splat, and four motion
//! films with motion blur) in [`WindowFilm`]s sharing `film_budget_mb` (tiles beyond it go
//! to a disk cache), the 2K + 2 scenes of the frame source, and one batch of
//! `TILES_PER_BATCH` tiles of contributions: bounded whatever the resolution and frame
//! count.
//!
//! Orthographic cameras: samples serve only their own frame (the landing test needs a
//! pinhole). The window holds at most [`MAX_WINDOW_FRAMES`] frames (K ≤ 31).

use crate::framework::integrator::RenderedFrame;
use crate::framework::integrator::SplattingEstimator;
use crate::framework::sequence::{ReuseStats, SequenceRenderer};
use crate::framework::window_film::{FilmStats, WindowFilm};
use crate::kernels::bdpt::{Bdpt, BdptSettings};
use chronolux_core::accel::multi_frame::MAX_WINDOW_FRAMES;
#[cfg(doc)]
use chronolux_core::accel::multi_frame::MultiFrameAccel;
use chronolux_core::color::Rgb;
use chronolux_core::math::Vec2;
use chronolux_core::parallel;
use chronolux_core::sampling::sampler::PixelSampler;
use chronolux_core::scene::frame::FrameScene;
use chronolux_core::scene::source::FrameSource;
use chronolux_core::stats::Stats;
use motion::splat_pixel_trajectories;
use std::collections::BTreeMap;
#[cfg(doc)]
use {
    crate::kernels::blur::splat_trajectory, chronolux_core::bsdf::Bsdf,
    chronolux_core::scene::delta::FrameDelta,
};

pub mod adapt;
mod context;
mod generation;
mod landing;
mod motion;
mod reuse;
pub mod strategies;

pub use generation::stream_index;

/// Settings of [`Stbpt`].
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StbptSettings {
    /// The per-sample estimator (samples per pixel generated per frame, depth, MIS, seed).
    pub bdpt: BdptSettings,
    /// Largest half-width K of the window [f − K, f + K] a sample serves (0 = frame by
    /// frame); with `adaptive`, each generated frame's K is chosen in 0..=window from the
    /// reuse statistics (module doc, "Choosing K"). Default 4. At most 31.
    pub window: u32,
    /// Choose K per generated frame from the reuse statistics, and BDPT's strategies or
    /// the path strategies from the pilot (true: module doc, "Choosing K" and "BDPT or
    /// the path strategies"); or always use `window` and the strategies of `bdpt` (false).
    /// Default true.
    #[serde(default = "adaptive_default")]
    pub adaptive: bool,
    /// Motion blur: fraction of the frame interval the shutter is open, centred on the
    /// frame time (0 = off). Each landed sample's trajectory is splatted (see "Motion
    /// blur" in the module doc). Default 0. Not a light-transport setting: set from the
    /// run's shutter when built, so it is not serialised with the technique's settings.
    #[serde(skip)]
    pub shutter: f32,
    /// Memory budget of the accumulation films in MiB (all open frames together); tiles
    /// beyond it go to a disk cache ([`WindowFilm::with_budget`]). Default 512.
    #[serde(default = "default_film_budget")]
    pub film_budget_mb: u64,
    /// Generated samples at part of the pixels (module doc, "Interleaved generation"):
    /// each frame generates its `spp` samples per pixel at one pixel in `interleave` (1,
    /// 2, 4, 8 or 16), the pattern shifting from frame to frame ([`generated_at`]) so that
    /// any `interleave` consecutive frames generate every pixel once; the window's landings
    /// serve the others. The effort below 1 sample per pixel and frame. Keep it at most
    /// the 2K + 1 frames of a window and the clip's length: a pixel that no frame of its
    /// window generates is filled in every frame (`reuse.filled` in `run.json`), which
    /// costs what frame-by-frame path tracing would there. Default 1.
    #[serde(default = "interleave_default", deserialize_with = "interleave_de")]
    pub interleave: u32,
}

fn interleave_default() -> u32 {
    1
}

fn interleave_de<'de, D: serde::Deserializer<'de>>(d: D) -> Result<u32, D::Error> {
    let v = <u32 as serde::Deserialize>::deserialize(d)?;
    if matches!(v, 1 | 2 | 4 | 8 | 16) {
        Ok(v)
    } else {
        Err(serde::de::Error::custom(format!(
            "interleave must be 1, 2, 4, 8 or 16 (one pixel in that many generates samples \
             per frame), not {v}"
        )))
    }
}

/// 4×4 Bayer matrix: its values below 16 / n, for n a power of two, form a regular
/// lattice of density 1 / n, and so do those in any of the n equal ranks.
const BAYER4: [u8; 16] = [0, 8, 2, 10, 12, 4, 14, 6, 3, 11, 1, 9, 15, 7, 13, 5];

/// Whether frame `f` generates samples at pixel (x, y) with [`StbptSettings::interleave`]
/// = `n`: pixel (x, y)'s rank in a 4×4 Bayer matrix over horizontal pixel pairs (x / 2,
/// y), of which frame f takes the (f mod n)-th of n equal rank ranges. Any n consecutive
/// frames generate every pixel once, each frame on a regular lattice of density 1 / n.
/// Pairs stay together so that the pilot's pair partners ([`strategies::pilot_pixel`])
/// are generated with each other; the grid frames (f a multiple of [`adapt::GRID`]) take
/// the lowest ranks, which for n ≤ 2 contain every pilot pair.
pub fn generated_at(x: u32, y: u32, f: u32, n: u32) -> bool {
    if n <= 1 {
        return true;
    }
    let r = BAYER4[((y & 3) * 4 + ((x >> 1) & 3)) as usize] as u32;
    r * n / 16 == f % n
}

fn default_film_budget() -> u64 {
    512
}

fn adaptive_default() -> bool {
    true
}

/// Samples per pixel generated per frame by default (see [`StbptSettings::default`]).
pub const DEFAULT_SPP: u32 = 4;

impl Default for StbptSettings {
    fn default() -> Self {
        StbptSettings {
            // 4 generated samples per pixel and frame, each landed in the 2K + 1 = 9
            // frames of its window: 36 per pixel served, which on the demo is cleaner than
            // frame-by-frame `path` at 64 spp for less CPU time (BENCHMARKS.md, "Issue 17:
            // the default") — the effort a first `render` should spend.
            bdpt: BdptSettings {
                common: crate::framework::technique::CommonSettings {
                    spp: DEFAULT_SPP,
                    ..BdptSettings::default().common
                },
                ..BdptSettings::default()
            },
            window: 4,
            adaptive: true,
            shutter: 0.0,
            film_budget_mb: default_film_budget(),
            interleave: 1,
        }
    }
}

/// Tiles of 16² pixels whose samples are made in one parallel batch before their
/// contributions are merged into the films: bounds the memory of in-flight contributions
/// (≈ 1024 tiles × 256 px × (2K + 1) frames × 3 films × 28 B ≈ 200 MB at K = 4) whatever
/// the resolution.
const TILES_PER_BATCH: usize = 1024;

/// Salts separating a sample's light and connection streams from its camera stream.
const LIGHT_STREAM: u64 = 0x9e37_79b9_7f4a_7c15;
const CONNECTION_STREAM: u64 = 0xc2b2_ae3d_27d4_eb4f;

/// What an output frame received so far.
#[derive(Clone, Debug, Default)]
struct Pending {
    stats: Stats,
    landed: u64,
    reused: u64,
    partial: u64,
    retraced: u64,
    retraced_prefix: u64,
    on_deformed: u64,
    invalid: u64,
    /// Generated frames whose samples served this frame.
    served_by: u32,
    /// Of those, the share of samples generated with light tracing (their splats: `spp`
    /// light subpaths per pixel for a whole frame) / with light subpaths (all BDPT
    /// strategies), summed over the generated frames (a pilot frame counts its share).
    served_by_lt: f64,
    served_by_light: f64,
}

/// Spatio-temporal BDPT; see the module documentation.
pub struct Stbpt {
    pub settings: StbptSettings,
    film: Option<WindowFilm>,
    /// Squares of the landed values (per-pixel variance of the weighted mean).
    film_sq: Option<WindowFilm>,
    /// Light-tracing splats (kept apart so the variance above is that of the landed
    /// samples).
    film_splat: Option<WindowFilm>,
    /// Motion blur: per pixel, the mean offsets and values of the landed samples in the
    /// neighbouring frames (empty without motion blur).
    film_blur: Vec<WindowFilm>,
    /// Index in the render list of the next frame to generate.
    next: usize,
    pending: BTreeMap<u32, Pending>,
    /// Mean number of frames served by the samples generated for each frame.
    served: BTreeMap<u32, f64>,
    last_output: Option<u32>,
    /// Per grid frame ([`adapt::GRID`]), the K and the strategies its measurement chose
    /// for the frames up to the next grid frame (module doc, "Choosing K").
    grid: BTreeMap<u32, (u32, strategies::Mode)>,
    /// The self-assessment of each generated frame, until the frame is output.
    decisions: BTreeMap<u32, adapt::WindowDecision>,
    /// The choice of strategies of each generated frame, until the frame is output.
    strategy_decisions: BTreeMap<u32, strategies::StrategyDecision>,
}

impl Stbpt {
    pub fn new(settings: StbptSettings) -> Self {
        Stbpt {
            grid: BTreeMap::new(),
            decisions: BTreeMap::new(),
            strategy_decisions: BTreeMap::new(),
            settings,
            film: None,
            film_sq: None,
            film_splat: None,
            film_blur: Vec::new(),
            next: 0,
            pending: BTreeMap::new(),
            served: BTreeMap::new(),
            last_output: None,
        }
    }

    /// The largest K (the `window` setting, capped by the multi-frame structure).
    fn k(&self) -> u32 {
        self.settings.window.min((MAX_WINDOW_FRAMES as u32 - 1) / 2)
    }

    /// Creates the films on first use: the memory budget is shared by the four films in
    /// proportion to what a pixel costs in each (the blur film only holds tiles when
    /// motion blur is on).
    fn open_films(&mut self, w: u32, h: u32) {
        if self.film.is_some() {
            return;
        }
        let budget = self.settings.film_budget_mb.max(1) << 20;
        let blur = if self.settings.shutter > 0.0 { 4 } else { 0 };
        let each = budget / (3 + blur);
        self.film = Some(WindowFilm::with_budget(w, h, each, None));
        self.film_sq = Some(WindowFilm::with_budget(w, h, each, None));
        self.film_splat = Some(WindowFilm::with_budget(w, h, each, None));
        self.film_blur = (0..blur)
            .map(|_| WindowFilm::with_budget(w, h, each, None))
            .collect();
    }

    /// Peak bytes held in memory by the films and their cache traffic (summed over the
    /// films; the peaks of different films may not coincide, so this is an upper bound).
    pub fn film_stats(&self) -> FilmStats {
        let mut t = FilmStats::default();
        let films = [&self.film, &self.film_sq, &self.film_splat];
        for f in films.into_iter().flatten().chain(&self.film_blur) {
            let s = f.stats();
            t.peak_bytes += s.peak_bytes;
            t.tile_hits += s.tile_hits;
            t.tile_misses += s.tile_misses;
            t.bytes_written += s.bytes_written;
            t.bytes_read += s.bytes_read;
            t.io_seconds += s.io_seconds;
            t.tiles_written += s.tiles_written;
            t.budget_bytes = t.budget_bytes.saturating_add(s.budget_bytes);
        }
        t
    }
}

/// What [`Stbpt::fill`] did.
struct Filled {
    /// The pixels filled.
    pixels: Vec<u32>,
    invalid: u64,
    stats: Stats,
}

/// Salt of the fill samples' stream (module doc, "Interleaved generation").
const FILL_STREAM: u64 = 0x1656_67b1_9e37_79f9;

impl Stbpt {
    /// Gives every pixel of `frame` that no landing reached (`weights` 0) `spp` samples of
    /// its own frame with the path strategies, from a stream of its own keyed by (seed,
    /// frame, pixel): their mean, weight and squares are written in place of the empty
    /// pixel's. Only with `interleave` > 1 can a pixel stay empty (otherwise its own
    /// sample lands in it).
    fn fill(
        &self,
        scene: &FrameScene,
        frame: u32,
        means: &mut [Rgb],
        weights: &mut [f32],
        squares: &mut [Rgb],
    ) -> Filled {
        let w = scene.camera.width;
        let empty: Vec<u32> = (0..weights.len() as u32)
            .filter(|&i| weights[i as usize] <= 0.0)
            .collect();
        let spp = self.settings.bdpt.common.spp.max(1);
        let bdpt = Bdpt::new(BdptSettings {
            light_tracing: false,
            path_strategies: true,
            ..self.settings.bdpt.clone()
        });
        let seed = self.settings.bdpt.common.seed ^ FILL_STREAM;
        let chunks = parallel::map_chunks(empty.len(), 64, |range| {
            let mut stats = Stats::default();
            let mut invalid = 0u64;
            let mut splats = Vec::new();
            let values: Vec<(Rgb, Rgb)> = empty[range]
                .iter()
                .map(|&i| {
                    let (x, y) = (i % w, i / w);
                    let mut sampler = PixelSampler::new(seed, frame, x, y);
                    let (mut sum, mut sq) = (Rgb::ZERO, Rgb::ZERO);
                    for s in 0..spp {
                        sampler.start_sample(s);
                        let raster = Vec2::new(x as f32, y as f32) + sampler.next_2d();
                        let v = bdpt.sample(scene, raster, &mut sampler, &mut stats, &mut splats);
                        stats.samples += 1;
                        if v.is_finite() {
                            sum += v;
                            sq += v * v;
                        } else {
                            invalid += 1;
                        }
                    }
                    (sum / spp as f32, sq / spp as f32)
                })
                .collect();
            (values, stats, invalid)
        });
        let mut out = Filled {
            pixels: Vec::new(),
            invalid: 0,
            stats: Stats::default(),
        };
        let mut values = chunks.iter().flat_map(|c| &c.0);
        for &i in &empty {
            let &(m, sq) = values.next().expect("one value per empty pixel");
            means[i as usize] = m;
            weights[i as usize] = spp as f32;
            squares[i as usize] = sq;
        }
        for c in &chunks {
            out.stats += c.1;
            out.invalid += c.2;
        }
        out.pixels = empty;
        out
    }
}

impl SequenceRenderer for Stbpt {
    fn name(&self) -> &'static str {
        "stbpt"
    }

    fn render_frame(
        &mut self,
        source: &mut FrameSource,
        frame: u32,
        progress: &(dyn Fn(u64) + Sync),
    ) -> RenderedFrame {
        let k = self.k();
        source.reserve(2 * k as usize + 2);
        let list = source.frames().to_vec();
        // Frames come in increasing order; a request for an earlier frame starts over
        // (the open frames are dropped, the samples regenerated).
        if self.last_output.is_some_and(|l| frame <= l) {
            *self = Stbpt::new(self.settings.clone());
        }
        if self.next == 0 {
            self.next = list.partition_point(|&g| g.saturating_add(k) < frame);
            let n = self.settings.interleave as usize;
            let frames = (2 * k as usize + 1).min(list.len());
            if n > frames {
                log::warn!(
                    "stbpt: interleave={n} is more than the {frames} frames a window holds here \
                     (2K + 1 = {}, clip {}): pixels that no frame of their window generates are \
                     path traced in every frame (reuse.filled in run.json); use interleave ≤ {frames}",
                    2 * k + 1,
                    list.len()
                );
            }
        }
        self.last_output = Some(frame);
        while self.next < list.len() && list[self.next] <= frame.saturating_add(k) {
            let f = list[self.next];
            // Every frame of f's window is still open: f > last output + k ≥ … + K_f.
            self.generate_next(source, f, progress);
            self.next += 1;
        }
        let p = self.pending.remove(&frame).unwrap_or_default();
        let window = p.served_by.max(1);
        let spp = self.settings.bdpt.common.spp;
        let scene = source.frame(frame);
        let (w, h) = (scene.camera.width, scene.camera.height);
        self.open_films(w, h);
        let (mut means, mut weights) = self.film.as_mut().expect("opened").finish(frame, 0.0);
        let (mut squares, _) = self.film_sq.as_mut().expect("opened").finish(frame, 0.0);
        // Pixels no landing reached (only with `interleave`: module doc, "Interleaved
        // generation") get samples of their own frame.
        let mut stats = p.stats;
        let mut invalid = p.invalid;
        let filled = self.fill(&scene, frame, &mut means, &mut weights, &mut squares);
        stats += filled.stats;
        invalid += filled.invalid;
        // The splats are the light-tracing share of the frames with light tracing: mean
        // over their light subpaths, weighted per pixel by their landings' share (module
        // doc, "BDPT or the path strategies"); all of the pixel when every frame had it.
        let lt = p.served_by_lt;
        let splat_scale = if lt > 0.0 {
            (1.0 / (spp as f64 * lt)) as f32
        } else {
            0.0
        };
        let (mut splats, lt_landed) = self
            .film_splat
            .as_mut()
            .expect("opened")
            .finish(frame, splat_scale);
        if lt > 0.0 && self.settings.adaptive {
            // The splat film's weights count the landings with light tracing (adaptive
            // runs only: the frames may differ in strategies); the fill's samples have none.
            if lt != window as f64 || !filled.pixels.is_empty() {
                for ((s, &nb), &n) in splats.iter_mut().zip(&lt_landed).zip(&weights) {
                    *s *= if n > 0.0 {
                        nb / n
                    } else {
                        (lt / window as f64) as f32
                    };
                }
            }
        } else if lt > 0.0 {
            // Every landing had light tracing but the fill's samples (path strategies), which
            // estimate all of their pixel's light.
            for &i in &filled.pixels {
                splats[i as usize] = Rgb::ZERO;
            }
        }
        if self.settings.shutter > 0.0 {
            let mut blur: Vec<Vec<Rgb>> = self
                .film_blur
                .iter_mut()
                .map(|f| f.finish(frame, 0.0).0)
                .collect();
            // A filled pixel has no trajectory: it is spread as a still one (offsets 0, its
            // value at both ends).
            for &i in &filled.pixels {
                let i = i as usize;
                blur[0][i] = Rgb::ZERO;
                blur[1][i] = Rgb::ZERO;
                blur[2][i] = means[i];
                blur[3][i] = means[i];
            }
            means = splat_pixel_trajectories(&means, &weights, &blur, w, h, self.settings.shutter);
        }
        // Variance of the mean of the landed samples, (E[v²] − E[v]²)/(n − 1); the splats'
        // share is not included (they are summed over many light subpaths).
        let variance = means
            .iter()
            .zip(&squares)
            .zip(&weights)
            .map(|((&m, &sq), &n)| {
                if n > 1.0 {
                    (sq - m * m).max(Rgb::ZERO) / (n - 1.0)
                } else {
                    Rgb::ZERO
                }
            })
            .collect();
        let pixels = means.iter().zip(&splats).map(|(&m, &s)| m + s).collect();
        let npix = (w as f64 * h as f64).max(1.0);
        let reuse = ReuseStats {
            window,
            effective_spp: p.landed as f64 / npix,
            reused: p.reused,
            reused_partially: p.partial,
            retraced: p.retraced,
            retraced_from_prefix: p.retraced_prefix,
            kept_on_deformed: p.on_deformed,
            reuse_factor: self.served.get(&frame).copied().unwrap_or(0.0),
            light_subpaths_per_pixel: spp as f64 * p.served_by_light,
            filled: filled.pixels.len() as u64,
            film: self.film_stats(),
        };
        self.served.retain(|&f, _| f + k >= frame);
        let mut report: crate::framework::integrator::Report = [(
            "reuse".to_string(),
            serde_json::to_value(reuse).expect("serialisable"),
        )]
        .into_iter()
        .collect();
        if let Some(d) = self.decisions.remove(&frame) {
            report.insert(
                "reuse_decision".to_string(),
                serde_json::to_value(d).expect("serialisable"),
            );
        }
        self.decisions.retain(|&f, _| f > frame);
        if let Some(d) = self.strategy_decisions.remove(&frame) {
            report.insert(
                "strategy_decision".to_string(),
                serde_json::to_value(d).expect("serialisable"),
            );
        }
        self.strategy_decisions.retain(|&f, _| f > frame);
        let mut out = RenderedFrame {
            width: w,
            height: h,
            pixels,
            variance,
            stats,
            invalid_samples: invalid,
            report,
            // The reused subpaths are not split into direct and indirect light.
            light: None,
        };
        // The served frame's caustics seen through glass: the reused samples' s = 0 drops
        // those paths (bdpt::connect_with), this frame's photons add them.
        crate::kernels::bdpt::caustic::add_caustics(&mut out, &scene, &self.settings.bdpt);
        out
    }
}

/// Registry entry of `stbpt`; the shutter is the run's ([`BuildContext`](crate::framework::technique::BuildContext)).
pub static TECHNIQUE: crate::framework::technique::Preset<StbptSettings> =
    crate::framework::technique::Preset {
        name: "stbpt",
        summary: "spatio-temporal BDPT: each sample reused in the frames of a window [f-K, f+K]",
        capabilities: crate::framework::technique::Capabilities {
            motion_blur: true,
            photons: false,
            window: true,
            max_depth: true,
            stateless: false,
            effort: crate::framework::technique::Effort {
                key: "spp",
                per_unit: 1,
                unit: "samples per pixel generated per frame",
            },
        },
        // Measured: BENCHMARKS.md, "The quality table" (window 8, interleave 8: its best route).
        quality: &[
            crate::framework::technique::QualityLevel::denoised(
                "draft",
                0.1044,
                &[("window", "8"), ("interleave", "8"), ("spp", "1")],
            ),
            crate::framework::technique::QualityLevel::denoised(
                "preview",
                0.0832,
                &[("window", "8"), ("interleave", "8"), ("spp", "2")],
            ),
            crate::framework::technique::QualityLevel::denoised(
                "final",
                0.0577,
                &[("window", "8"), ("interleave", "8"), ("spp", "8")],
            ),
        ],
        defaults: StbptSettings::default,
        common: |s| &mut s.bdpt.common,
        build: |mut s, ctx, _| {
            s.shutter = ctx.shutter;
            Ok(Box::new(Stbpt::new(s)))
        },
    };
