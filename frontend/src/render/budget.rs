//! The work a render may do, estimated before it starts: the worst-case ray count from the
//! scene's settings in the render's mode, the largest group of coincident objects, and a rough
//! time. `--explain` prints it; `render` refuses a scene whose worst case is over
//! [`MAX_WORST_CASE_WORK`] unless `--allow-long`.
//!
//! The worst case per pixel is `S × (1 + R) × (1 + L × T)`, each factor read from the effects
//! the render runs in its mode ([`EffectPlan::flags`], the flags `--stats-json` reports): `S`
//! camera rays (`lens_samples` with depth of field, else the anti-aliasing samples with
//! anti-aliasing, else 1), each with at most `R` secondary rays (below) and at every one of
//! those shading points `L` shadow rays (with shadow rays: one per point or directional light
//! the plan casts them towards, `samples` per area light; else 0), each traced as at most `T`
//! segments (`MAX_SHADOW_CROSSINGS + 1` = 17 with shadow transmission, where a shadow ray
//! continues past every transparent surface it crosses as a new segment, each counted as a
//! shadow ray: one segment to each of at most [`MAX_SHADOW_CROSSINGS`] surfaces crossed and the
//! last; else 1). Outside colour mode none of these effects runs, so the worst case there is one ray
//! per pixel.
//!
//! `R` bounds the camera ray's tree ([`super::trace`]). Its traced rays number at most `N`:
//! [`MAX_SECONDARY_RAYS_PER_CAMERA_RAY`] where the scene's own plan ([`EffectPlan::derive`] without
//! force) casts reflection or refraction rays in the mode, else 0; a forced render traces the
//! same tree. Without `--force-all-effects`, `R = N`. With it, where the forced plan casts
//! reflection or refraction rays, every node that expands (the camera ray's hit and each traced
//! ray's, at most `1 + N`) casts at most one reflection and one refraction ray, each traced or a
//! leaf (an effect its material does not have), so `R = 2 × (1 + N)`; a leaf's hit is a
//! shading point like any other.
//!
//! Real renders cast far fewer (adaptive anti-aliasing, path weights that fall below the
//! bound, shadow rays that meet no transparent surface), so the estimate is an upper bound,
//! not a prediction.
//!
//! Coincident objects (copies with the same world box, as `repeat` with a zero `step` makes)
//! cannot be told apart by the top-level BVH: a box test cannot skip one copy without skipping
//! all, and which copy is hit first (and so which material shows) is decided only by
//! intersecting each. So every ray that reaches such a group tests all of its objects; the
//! estimate multiplies the rays by the size of the largest group.

use super::Mode;
use super::bound::MAX_SECONDARY_RAYS_PER_CAMERA_RAY;
use super::plan::{EffectPlan, PlanFlags};
use super::trace::MAX_SHADOW_CROSSINGS;
use crate::scene::{LightKind, Scene};
use std::collections::HashMap;

/// Largest worst-case work (rays × the largest coincident group) `render` starts without
/// `--allow-long`: 10¹¹, about a day at [`ASSUMED_RAYS_PER_SECOND`] on one thread. The
/// shipped scenes' worst cases are at most 2.3·10¹⁰ (`glass.toml` and `showcase.toml`, whose
/// shadow rays pass through glass: 17 segments each; `mirror.toml` 2.5·10⁹), so those two
/// need `--allow-long` from `--samples 5` on.
pub const MAX_WORST_CASE_WORK: f64 = 1e11;

/// Rays per second per thread the time estimate assumes: 10⁶, the order the showcase renders
/// at (about 1 Mrays/s on one core of the development machines). A rough figure: meshes,
/// CSG and transparency change it.
pub const ASSUMED_RAYS_PER_SECOND: f64 = 1e6;

/// A render's estimated work (see the module docs). Counts are `f64`: a worst case beyond
/// 2⁶⁴ is still ordered right.
#[derive(Clone, Debug, PartialEq)]
pub struct Estimate {
    /// Pixels.
    pub pixels: f64,
    /// Camera rays per pixel (`S`).
    pub camera_rays: f64,
    /// Most secondary rays per camera ray (`R`): traced and, forced, leaf rays.
    pub secondary: f64,
    /// Shadow rays per shading point (`L`).
    pub shadow: f64,
    /// Most segments each shadow ray is traced as (`T`): `MAX_SHADOW_CROSSINGS + 1` with
    /// shadow transmission (one per surface crossed, and the last), else 1.
    pub segments: f64,
    /// Objects in the largest group sharing one world box.
    pub coincident: usize,
}

impl Estimate {
    /// The estimate of `scene` rendered with `plan` in `mode` with at most `samples`
    /// anti-aliasing samples per pixel: the factors of the effects that render runs
    /// ([`EffectPlan::flags`]), see the module docs.
    pub fn of(scene: &Scene, plan: &EffectPlan, mode: Mode, samples: u32) -> Self {
        let cam = &scene.camera;
        let runs = plan.flags(scene, mode, samples);
        let camera_rays = match &cam.lens {
            Some(lens) if runs.depth_of_field => lens.samples,
            _ if runs.antialias => samples,
            _ => 1,
        };
        let secondary_runs = |f: PlanFlags| f.reflection || f.refraction;
        let own = if plan.forced {
            EffectPlan::derive(scene, false).flags(scene, mode, samples)
        } else {
            runs
        };
        let traced = if secondary_runs(own) {
            MAX_SECONDARY_RAYS_PER_CAMERA_RAY
        } else {
            0
        };
        let secondary = if plan.forced && secondary_runs(runs) {
            2 * (1 + traced)
        } else {
            traced
        };
        // Summed from +0: `Iterator::sum` of no `f64` is −0, printed as "-0".
        let shadow = scene
            .lights
            .iter()
            .zip(&plan.shadow_rays)
            .filter(|(_, on)| runs.shadow && **on)
            .map(|(l, _)| match l.kind {
                LightKind::Point { .. } if l.radius > 0.0 => f64::from(l.samples),
                _ => 1.0,
            })
            .fold(0.0, |sum, n| sum + n);
        let segments = if runs.shadow_transmission {
            MAX_SHADOW_CROSSINGS + 1
        } else {
            1
        };
        let mut boxes: HashMap<[u32; 6], usize> = HashMap::new();
        for o in &scene.objects {
            if let Some(b) = o.bounds {
                let key = [b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z].map(f32::to_bits);
                *boxes.entry(key).or_default() += 1;
            }
        }
        Self {
            pixels: f64::from(cam.width) * f64::from(cam.height),
            camera_rays: f64::from(camera_rays),
            secondary: f64::from(secondary),
            shadow,
            segments: f64::from(segments),
            coincident: boxes.values().copied().max().unwrap_or(0),
        }
    }

    /// Worst-case rays of the whole image: `pixels × S × (1 + R) × (1 + L × T)`.
    pub fn rays(&self) -> f64 {
        self.pixels
            * self.camera_rays
            * (1.0 + self.secondary)
            * (1.0 + self.shadow * self.segments)
    }

    /// Worst-case work: rays × the largest coincident group (at least 1).
    pub fn work(&self) -> f64 {
        self.rays() * self.coincident.max(1) as f64
    }

    /// Rough seconds on `threads` threads at [`ASSUMED_RAYS_PER_SECOND`].
    pub fn seconds(&self, threads: usize) -> f64 {
        self.work() / (ASSUMED_RAYS_PER_SECOND * threads.max(1) as f64)
    }

    /// Whether the work is over [`MAX_WORST_CASE_WORK`].
    pub fn over_budget(&self) -> bool {
        self.work() > MAX_WORST_CASE_WORK
    }

    /// The `--explain` lines.
    pub fn explain(&self, threads: usize) -> String {
        let segments = if self.segments > 1.0 {
            format!(" × {} segments", self.segments)
        } else {
            String::new()
        };
        let mut s = format!(
            "  worst case       {:.3e} rays = {} pixels × {} camera rays × (1 + {} secondary) × (1 + {} shadow rays per hit{segments})\n",
            self.rays(),
            self.pixels,
            self.camera_rays,
            self.secondary,
            self.shadow
        );
        if self.coincident > 1 {
            s.push_str(&format!(
                "  coincident       {} objects share one box: each ray reaching them tests all (the top-level BVH cannot skip identical boxes)\n",
                self.coincident
            ));
        }
        s.push_str(&format!(
            "  time estimate    at most about {} on {threads} threads (assuming {:.0e} rays/s per thread); budget {:.0e} (--allow-long past it)\n",
            duration(self.seconds(threads)),
            ASSUMED_RAYS_PER_SECOND,
            MAX_WORST_CASE_WORK
        ));
        s
    }
}

/// `seconds` in the largest fitting unit (`3.2 s`, `4.1 h`, `12.0 days`).
pub fn duration(seconds: f64) -> String {
    match seconds {
        s if s < 120.0 => format!("{s:.1} s"),
        s if s < 7200.0 => format!("{:.1} min", s / 60.0),
        s if s < 172_800.0 => format!("{:.1} h", s / 3600.0),
        s => format!("{:.1} days", s / 86_400.0),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_worst_case_multiplies_out() {
        let e = Estimate {
            pixels: 640.0 * 480.0,
            camera_rays: 256.0,
            secondary: 4096.0,
            shadow: 64.0 * 256.0,
            segments: 1.0,
            coincident: 1,
        };
        // 256 × 4097 × 16385 rays per pixel: 17.2 G, far over the budget.
        assert_eq!(e.rays(), 307_200.0 * 256.0 * 4097.0 * 16_385.0);
        assert!(e.over_budget());
        assert_eq!(duration(90.0), "90.0 s");
        assert_eq!(duration(86_400.0 * 10.0), "10.0 days");
        let small = Estimate {
            pixels: 768.0,
            camera_rays: 1.0,
            secondary: 0.0,
            shadow: 0.0,
            segments: 1.0,
            coincident: 1_000_000,
        };
        assert_eq!(small.work(), 768e6);
        assert!(small.explain(2).contains("1000000 objects share one box"));
        // Seconds: the work over the assumed rate of every thread.
        assert_eq!(small.seconds(4), 768e6 / (ASSUMED_RAYS_PER_SECOND * 4.0));
        assert_eq!(small.seconds(0), small.seconds(1));
    }

    /// `mirror.toml` with each `(from, to)` of `edits` replaced.
    fn mirror_scene(edits: &[(&str, &str)]) -> Scene {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/mirror.toml");
        let mut text = std::fs::read_to_string(&path).unwrap();
        for (from, to) in edits {
            assert!(text.contains(from), "{from} in {}", path.display());
            text = text.replace(from, to);
        }
        crate::scene::parse(&text, &path).unwrap()
    }

    /// The secondary rays per camera ray of a colour render of `scene`, forced or not.
    fn secondary(scene: &Scene, force_all: bool) -> f64 {
        let plan = EffectPlan::derive(scene, force_all);
        Estimate::of(scene, &plan, Mode::Color, 1).secondary
    }

    /// A scene with a mirror counts the secondary rays it may cast; the same scene with its
    /// reflections off (`max_depth = 0`) counts none.
    #[test]
    fn secondary_rays_are_counted_where_the_plan_traces_them() {
        let mirror = mirror_scene(&[]);
        assert_eq!(
            secondary(&mirror, false),
            f64::from(MAX_SECONDARY_RAYS_PER_CAMERA_RAY)
        );
        let flat = mirror_scene(&[("max_depth = 4", "max_depth = 0")]);
        assert_eq!(secondary(&flat, false), 0.0);
    }

    /// Forced, every node of the tree that expands casts a reflection and a refraction ray,
    /// traced or a leaf: the mirror scene's camera ray's hit and each of its 4096 traced rays',
    /// `2 × (1 + 4096)`; with the mirror matte, only the camera ray's hit, 2; with
    /// `max_depth = 0`, none.
    #[test]
    fn forced_leaf_rays_are_counted_for_every_node_that_expands() {
        let nodes = 1.0 + f64::from(MAX_SECONDARY_RAYS_PER_CAMERA_RAY);
        assert_eq!(secondary(&mirror_scene(&[]), true), 2.0 * nodes);
        assert_eq!(
            secondary(&mirror_scene(&[("mirror = 0.9", "mirror = 0")]), true),
            2.0
        );
        assert_eq!(
            secondary(&mirror_scene(&[("max_depth = 4", "max_depth = 0")]), true),
            0.0
        );
    }

    /// Without a light that casts shadows the estimate's shadow rays per hit print as `0`.
    #[test]
    fn no_shadow_rays_print_as_zero() {
        let scene = mirror_scene(&[("[[light]]", "[[light]]\ncast_shadows = false")]);
        let plan = EffectPlan::derive(&scene, false);
        assert!(plan.shadow_rays.iter().all(|&on| !on));
        let explain = Estimate::of(&scene, &plan, Mode::Color, 1).explain(1);
        assert!(
            explain.contains("× (1 + 0 shadow rays per hit)"),
            "{explain}"
        );
    }
}
