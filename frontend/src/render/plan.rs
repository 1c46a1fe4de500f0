//! The effect plan: which effects the scene calls for, derived before rendering, so that the
//! renderer simulates only those. `--force-all-effects` switches everything on (the results of
//! effects the scene does not use are computed and then discarded, so the picture is the same
//! in every mode but the heat map, which shows the work done; only the work differs).

use super::Mode;
use super::bound::{MAX_SECONDARY_RAYS_PER_CAMERA_RAY, MIN_PATH_WEIGHT, PathBound};
use crate::scene::{LightKind, Material, Scene};
use std::fmt::Write as _;

/// What the renderer will simulate.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct EffectPlan {
    /// Per light: cast shadow rays towards it (not for `cast_shadows = false`, nor for a light
    /// of zero intensity or colour, whose contribution is zero lit or not).
    pub shadow_rays: Vec<bool>,
    /// Per material: evaluate the Blinn–Phong specular term.
    pub specular: Vec<bool>,
    /// Per material: evaluate the lights' direct term (diffuse and specular) and cast shadow
    /// rays from its surfaces: its `diffuse` is not 0 or its specular term is evaluated (else
    /// the term is 0, lit or not).
    pub direct: Vec<bool>,
    /// Per material: cast reflection rays: its `mirror` casts them ([`mirror_casts`]), or
    /// its `transparency` does and `ior ≠ 1` (total internal reflection; at `ior = 1` every
    /// ray refracts).
    pub reflect: Vec<bool>,
    /// Per material: cast refraction rays: its `transparency` casts them ([`mirror_casts`]'s
    /// rule).
    pub refract: Vec<bool>,
    /// Largest recursion depth used (0 when no material reflects or refracts).
    pub max_depth: u32,
    /// Shadow rays pass through transparent surfaces, each crossing multiplying the light by
    /// the material's `transparency` (on when an object with a transparent material can
    /// shadow something: some light casts shadows; else shadow rays stop at the first hit).
    pub shadow_transmission: bool,
    /// Evaluate every solid through the CSG interval path (only with `force_all`).
    pub intervals_everywhere: bool,
    /// Labels of the CSG objects (always interval-evaluated).
    pub csg_objects: Vec<String>,
    /// `--force-all-effects`.
    pub forced: bool,
}

/// The plan as `--stats-json` reports it: one boolean per effect, `true` when the renderer
/// simulates it for some light, material or object in the render's mode ([`EffectPlan::flags`]):
/// outside colour mode only `csg_intervals` can be `true` (the geometry every mode hits).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct PlanFlags {
    /// Shadow rays towards at least one light, from at least one material.
    pub shadow: bool,
    /// Reflection rays for at least one material (never with `max_depth = 0`).
    pub reflection: bool,
    /// Refraction rays for at least one material (never with `max_depth = 0`).
    pub refraction: bool,
    /// The specular term for at least one material (and at least one light: the term is
    /// evaluated per light).
    pub specular: bool,
    /// Shadow rays through transparent surfaces ([`EffectPlan::shadow_transmission`]).
    pub shadow_transmission: bool,
    /// More than one sample per pixel where the image needs it (`samples > 1` without a
    /// lens).
    pub antialias: bool,
    /// CSG interval evaluation (CSG objects, or every solid when forced).
    pub csg_intervals: bool,
    /// Soft shadows: shadow rays over the disk of at least one point light with `radius > 0`.
    pub area_lights: bool,
    /// A thin-lens camera (`aperture > 0`): every pixel through `lens_samples` lens positions.
    pub depth_of_field: bool,
}

/// Whether the tracer can cast a reflection ray for `m`'s `mirror`: under the render's bound
/// from the camera ray's hit ([`PathBound::casts`] at weight 1), so never for a `mirror`
/// below [`MIN_PATH_WEIGHT`].
pub fn mirror_casts(m: &Material) -> bool {
    PathBound::RENDER.casts(1.0, m.mirror)
}

/// Whether the tracer can cast a refraction ray for `m`'s `transparency` ([`mirror_casts`]'s
/// rule).
pub fn transparency_casts(m: &Material) -> bool {
    PathBound::RENDER.casts(1.0, m.transparency)
}

/// Whether `m`'s transmitted ray can be totally internally reflected: it is cast
/// ([`transparency_casts`]) and `ior ≠ 1` (at `ior = 1` Snell's `k = 1 − (1 − cos²θ)` is
/// never negative: every ray refracts, straight on).
pub fn total_internal_reflects(m: &Material) -> bool {
    transparency_casts(m) && m.ior != 1.0
}

impl EffectPlan {
    /// One flag per effect of a render of `scene` (this plan's) in `mode` with at most
    /// `samples` samples per pixel, for `--stats-json`: `true` only for an effect that runs.
    /// Shading (shadows, specular, reflection, refraction, area lights) and the extra camera
    /// rays (anti-aliasing, depth of field) run in colour mode only; reflection and refraction
    /// need a recursion depth above 0; shadow rays a light that casts them and a material with
    /// a direct term ([`EffectPlan::direct`]).
    pub fn flags(&self, scene: &Scene, mode: Mode, samples: u32) -> PlanFlags {
        let color = mode == Mode::Color;
        let any = |v: &[bool]| v.iter().any(|&b| b);
        let recursive = color && self.max_depth > 0;
        let shadow = color && any(&self.shadow_rays) && any(&self.direct);
        let lens = scene.camera.lens.is_some();
        PlanFlags {
            shadow,
            reflection: recursive && any(&self.reflect),
            refraction: recursive && any(&self.refract),
            // Evaluated per light (`Tracer`'s light loop): none without a light.
            specular: color && any(&self.specular) && !scene.lights.is_empty(),
            shadow_transmission: shadow && self.shadow_transmission,
            antialias: color && samples > 1 && !lens,
            area_lights: shadow
                && scene
                    .lights
                    .iter()
                    .zip(&self.shadow_rays)
                    .any(|(l, &on)| on && l.radius > 0.0),
            depth_of_field: color && lens,
            csg_intervals: self.intervals_everywhere || !self.csg_objects.is_empty(),
        }
    }

    /// The plan the scene calls for, or everything when `force_all`.
    pub fn derive(scene: &Scene, force_all: bool) -> Self {
        let mats = &scene.materials;
        // Effects follow the materials objects use, not every material declared.
        let used = scene.used_materials();
        let reflect: Vec<bool> = mats
            .iter()
            .zip(&used)
            .map(|(m, &u)| force_all || (u && (mirror_casts(m) || total_internal_reflects(m))))
            .collect();
        let refract: Vec<bool> = mats
            .iter()
            .zip(&used)
            .map(|(m, &u)| force_all || (u && transparency_casts(m)))
            .collect();
        let recursive = reflect.iter().chain(&refract).any(|&b| b);
        let shadow_rays: Vec<bool> = scene
            .lights
            .iter()
            .map(|l| force_all || (l.cast_shadows && l.intensity != glam::Vec3::ZERO))
            .collect();
        let transparent_used = mats
            .iter()
            .zip(&used)
            .any(|(m, &u)| u && m.transparency > 0.0);
        let specular: Vec<bool> = mats
            .iter()
            .zip(&used)
            .map(|(m, &u)| force_all || (u && m.has_specular()))
            .collect();
        let direct = mats
            .iter()
            .zip(&used)
            .zip(&specular)
            .map(|((m, &u), &s)| force_all || (u && (m.diffuse != glam::Vec3::ZERO || s)))
            .collect();
        Self {
            shadow_transmission: force_all || (transparent_used && shadow_rays.iter().any(|&b| b)),
            shadow_rays,
            specular,
            direct,
            reflect,
            refract,
            max_depth: if recursive { scene.max_depth } else { 0 },
            intervals_everywhere: force_all,
            csg_objects: scene.csg_objects().iter().map(|s| s.to_string()).collect(),
            forced: force_all,
        }
    }

    /// The human-readable plan (`--explain`) of a render of `scene` in `mode` with at most
    /// `samples` samples per pixel: what that render simulates, decided by the same flags as
    /// `--stats-json` and the work estimate ([`EffectPlan::flags`]). An effect that does not
    /// run prints as `none` (or `off`) with the reason: outside colour mode, the mode's one ray
    /// per pixel; in colour, the lights, materials or depth that leave nothing to simulate.
    pub fn explain(&self, scene: &Scene, mode: Mode, samples: u32) -> String {
        let mut s = String::new();
        let used = scene.used_materials();
        let cam = &scene.camera;
        let runs = self.flags(scene, mode, samples);
        // Outside colour mode: why no shading effect runs.
        let one_ray = (mode != Mode::Color).then(|| {
            let name = clap::ValueEnum::to_possible_value(&mode)
                .map_or_else(|| format!("{mode:?}"), |v| v.get_name().to_string());
            format!("mode {name}: one ray per pixel")
        });
        // Names and paths from the scene are escaped (`crate::text::escaped`): no control
        // character of theirs reaches the terminal or starts a line of its own.
        let esc = crate::text::escaped;
        let _ = writeln!(
            s,
            "effect plan for {}{}:",
            crate::text::path(&scene.path),
            if self.forced {
                " (--force-all-effects: every effect on)"
            } else {
                ""
            }
        );
        let pixels = u64::from(cam.width) * u64::from(cam.height);
        let primary = match (&cam.lens, runs.depth_of_field, runs.antialias) {
            (Some(lens), true, _) => format!(
                "{} × {} × {} = {} (depth of field: {} a pixel, each through its own lens and sub-pixel position; aperture {}, focused at {})",
                cam.width,
                cam.height,
                lens.samples,
                pixels * u64::from(lens.samples),
                lens.samples,
                lens.aperture,
                lens.focus_distance
            ),
            (_, _, true) => format!(
                "{} × {} = {pixels} through the pixel centres, then up to {} more in each pixel that differs from a neighbour (adaptive anti-aliasing, at most {samples} a pixel)",
                cam.width,
                cam.height,
                samples - 1
            ),
            _ => format!(
                "{} × {} = {pixels} (one per pixel, through its centre)",
                cam.width, cam.height
            ),
        };
        let _ = writeln!(s, "  primary rays     {primary}");
        let names = |pick: &dyn Fn(usize) -> bool, n: usize, label: &dyn Fn(usize) -> String| {
            (0..n).filter(|&i| pick(i)).map(label).collect::<Vec<_>>()
        };
        let light_label = |i: usize| {
            let l = &scene.lights[i];
            let kind = match l.kind {
                LightKind::Point { .. } if l.radius > 0.0 => format!(
                    "point, area: radius {}, {} shadow rays over its disk",
                    l.radius, l.samples
                ),
                LightKind::Point { .. } => "point".to_string(),
                LightKind::Directional { .. } => "directional".to_string(),
            };
            format!("{} ({kind})", esc(&l.name))
        };
        let nl = scene.lights.len();
        let on = names(&|i| self.shadow_rays[i], nl, &light_label);
        let off_label = |i: usize| {
            let why = if scene.lights[i].intensity == glam::Vec3::ZERO {
                "zero intensity or colour: contributes nothing"
            } else {
                "cast_shadows = false"
            };
            format!("{} ({why})", light_label(i))
        };
        let off = names(&|i| !self.shadow_rays[i], nl, &off_label);
        let skipped = if off.is_empty() {
            String::new()
        } else {
            format!("; skipped for {}", off.join(", "))
        };
        let shadow_line = match &one_ray {
            Some(why) => format!("none ({why})"),
            None if runs.shadow => format!("towards {}{skipped}", on.join(", ")),
            None if on.is_empty() => format!("none{skipped}"),
            None => format!(
                "none (no used material has a direct term, so none towards {}){skipped}",
                on.join(", ")
            ),
        };
        let _ = writeln!(s, "  shadow rays      {shadow_line}");
        let unlit: Vec<String> = names(
            &|i| !self.direct[i] && used[i],
            scene.materials.len(),
            &|i| esc(&scene.materials[i].name),
        );
        if one_ray.is_none() && !on.is_empty() && !unlit.is_empty() {
            let _ = writeln!(
                s,
                "  direct lighting  skipped on {} (diffuse 0, no specular: no shadow rays from them)",
                unlit.join(", ")
            );
        }
        let _ = writeln!(
            s,
            "  shadow transmission {}",
            match &one_ray {
                Some(why) => format!("off ({why})"),
                None if runs.shadow_transmission => "on: shadow rays continue through transparent surfaces, light × transparency per crossing".to_string(),
                None if !runs.shadow => "off: no shadow rays".to_string(),
                None => "off: no object uses a transparent material (shadow rays stop at the first hit)".to_string(),
            }
        );
        let nm = scene.materials.len();
        let mat = |i: usize| esc(&scene.materials[i].name);
        let list = |v: Vec<String>| {
            if v.is_empty() {
                "none".to_string()
            } else {
                v.join(", ")
            }
        };
        let specular_line = match &one_ray {
            Some(why) => format!("none ({why})"),
            None if scene.lights.is_empty() => "none (no lights)".to_string(),
            None if self.forced => list(names(&|i| self.specular[i], nm, &mat)),
            None => format!(
                "{} (skipped where ks = 0: {})",
                list(names(&|i| self.specular[i], nm, &mat)),
                list(names(&|i| used[i] && !self.specular[i], nm, &mat))
            ),
        };
        let _ = writeln!(s, "  specular term    {specular_line}");
        let reflect_label = |i: usize| {
            let m = &scene.materials[i];
            let name = esc(&m.name);
            if mirror_casts(m) {
                format!("{name} (mirror {})", m.mirror)
            } else if total_internal_reflects(m) {
                format!("{name} (total internal reflection only)")
            } else {
                format!("{name} (forced, weight 0)")
            }
        };
        let refract_label = |i: usize| {
            let m = &scene.materials[i];
            let name = esc(&m.name);
            if transparency_casts(m) {
                format!("{name} (transparency {}, ior {})", m.transparency, m.ior)
            } else {
                format!("{name} (forced, weight 0)")
            }
        };
        // Each material that casts them, where they run (`runs`); else `none` and, outside
        // colour mode, why.
        let secondary = |on: bool, pick: &[bool], label: &dyn Fn(usize) -> String| match &one_ray {
            Some(why) => format!("none ({why})"),
            None if on => list(names(&|i| pick[i], nm, label)),
            None => "none".to_string(),
        };
        let _ = writeln!(
            s,
            "  reflection rays  {}",
            secondary(runs.reflection, &self.reflect, &reflect_label)
        );
        let _ = writeln!(
            s,
            "  refraction rays  {}",
            secondary(runs.refraction, &self.refract, &refract_label)
        );
        let unused: Vec<String> = used
            .iter()
            .enumerate()
            .filter(|&(_, &u)| !u)
            .map(|(i, _)| mat(i))
            .collect();
        if !unused.is_empty() {
            let _ = writeln!(
                s,
                "  unused materials {} (no object uses them: no effect of theirs is simulated)",
                unused.join(", ")
            );
        }
        let recursive = runs.reflection || runs.refraction;
        let _ = writeln!(
            s,
            "  recursion depth  {}",
            match &one_ray {
                Some(why) => format!("0 ({why}; scene max_depth {})", scene.max_depth),
                None if recursive => format!("{} (scene max_depth)", self.max_depth),
                None if scene.max_depth == 0 => "0 (scene max_depth 0)".to_string(),
                None => format!(
                    "0 (no mirror or transparent material; scene max_depth {})",
                    scene.max_depth
                ),
            }
        );
        if recursive {
            let _ = writeln!(
                s,
                "  ray tree bound   a secondary ray is cast only while its path weight (product of mirror/transparency factors) is ≥ 1/{} (below, it cannot move an 8-bit sRGB value of display-range radiance), and at most {} reflection + refraction rays per camera ray (for each of a pixel's camera rays)",
                (1.0 / MIN_PATH_WEIGHT) as u32,
                MAX_SECONDARY_RAYS_PER_CAMERA_RAY
            );
        }
        let _ = writeln!(
            s,
            "  CSG intervals    {}",
            if self.intervals_everywhere {
                "every solid (forced)".to_string()
            } else if self.csg_objects.is_empty() {
                "none (no CSG objects)".to_string()
            } else {
                let labels: Vec<String> = self.csg_objects.iter().map(|l| esc(l)).collect();
                labels.join(", ")
            }
        );
        s
    }
}
