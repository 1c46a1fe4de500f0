//! Whitted-style ray tracing under an [`EffectPlan`].
//!
//! `L = ka·Ia + Σ_lights [kd·E·max(0, n·l) + ks·E·max(0, n·h)^p] + kr·L(reflected) + kt·L(refracted)`
//! with `E = I/r²` for point lights and `E = I` for directional ones, `n` the normal facing the
//! incoming ray, `h = normalize(l + v)`. A point or directional light contributes nothing where
//! `n·l ≤ 0` (the surface faces away from it) or where a shadow ray finds an occluder (lights
//! with `cast_shadows`). An area light (a point light with `radius > 0` that casts shadows) is
//! the mean over its disk's sample points of the same term, `l` the direction to each point,
//! with `E` its centre's: a point on or below the surface's tangent plane, or behind an
//! occluder, adds nothing (`Tracer::area_light`), so a disk whose centre is below the plane
//! still lights the surface with the part above it. No shadow ray is cast from a material whose
//! direct term is 0 whatever the light (`diffuse` 0 and no specular: [`EffectPlan::direct`]).
//! Shadow rays are any-hit queries started with the core's robust spawn ([`spawn_ray_to`] /
//! [`spawn_ray`]), never with a scene epsilon.
//!
//! # What bounds the ray tree
//! A material with both `mirror` and `transparency` casts two rays per hit, so the tree is
//! exponential in `max_depth`. A [`PathBound`] cuts it: a secondary ray is cast only while its
//! path weight (the product of the `mirror`/`transparency` factors from the camera) is at least
//! [`MIN_PATH_WEIGHT`](super::bound::MIN_PATH_WEIGHT), and at most
//! [`MAX_SECONDARY_RAYS_PER_CAMERA_RAY`](super::bound::MAX_SECONDARY_RAYS_PER_CAMERA_RAY)
//! reflection and refraction rays are cast per camera ray (depth first; the rest count as
//! zero), so a pixel of several camera rays (lens or anti-aliasing samples) casts up to that
//! many for each. The weight test alone keeps the tree at most `max_depth / MIN_PATH_WEIGHT`
//! rays when `mirror + transparency ≤ 1`; the cap per camera ray bounds the rest (both factors
//! up to 1 are accepted).
//!
//! Under `--force-all-effects`, the rays of effects a material does not have (weight 0) are
//! cast from every node the plain plan expands, as leaves: they do the work, their result is
//! discarded (not multiplied by zero: `0·∞` would be NaN), and they use none of the camera
//! ray's budget, so the picture is the plan's, bit for bit. The work estimate counts them
//! ([`super::budget`]).

use super::bound::PathBound;
use super::plan::EffectPlan;
use crate::scene::geom::{QueryCtx, SurfaceHit};
use crate::scene::{Light, LightKind, Scene, SpecularModel};
use glam::Vec3;
use halfray_core::{Aabb, Ray, shadow_segment, spawn_ray, spawn_ray_to};

/// Transparent surfaces a shadow ray crosses before it counts the light as blocked: 16
/// crossings (8 panes of glass) transmit `transparency¹⁶`, and a surface met after them (a 17th)
/// blocks the light; `transparency¹⁶` is below an 8-bit step for any transparency up to 0.7, so
/// the cut-off shows only behind nearly clear glass. The bound keeps the walk finite for any
/// scene: a shadow ray is traced as at most `MAX_SHADOW_CROSSINGS + 1` segments (one to each
/// surface crossed, and the last, towards the light).
pub const MAX_SHADOW_CROSSINGS: u32 = 16;

/// Most bounded objects an area light's shadow rays from one hit are tested against directly
/// ([`crate::scene::top::TopLevel::bounded_in`]); more, and each ray walks the top level. A
/// count of objects: a direct test costs about what a walk's visit of that object does.
pub const HULL_OBJECTS_MAX: usize = 4;

/// Where a path is: recursion depth, weight, and its camera ray's remaining secondary rays.
struct PathState {
    depth: u32,
    weight: f32,
    bound: PathBound,
    rays_left: u32,
}

impl PathState {
    /// A path starting at recursion `depth` with weight 1 under `bound`.
    fn new(depth: u32, bound: PathBound) -> Self {
        Self {
            depth,
            weight: 1.0,
            bound,
            rays_left: bound.max_secondary_rays,
        }
    }

    /// Whether this node may cast secondary rays at all (forced leaves may not).
    fn expands(&self, max_depth: u32) -> bool {
        self.depth < max_depth && self.weight > 0.0 && self.weight >= self.bound.min_weight
    }
}

/// What happened to a secondary ray.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Cast {
    /// Not cast (weight or budget exhausted, or no such effect).
    Skipped,
    /// Cast for `--force-all-effects` only; its result is not used.
    Leaf,
    /// Traced; its radiance.
    Traced(Vec3),
}

/// Rays cast, per kind.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct RayCounts {
    /// Camera rays.
    pub primary: u64,
    /// Shadow (occlusion) rays.
    pub shadow: u64,
    /// Mirror reflection rays (including total internal reflection).
    pub reflection: u64,
    /// Refraction rays.
    pub refraction: u64,
}

impl RayCounts {
    /// Sum of all kinds.
    pub fn total(&self) -> u64 {
        self.primary + self.shadow + self.reflection + self.refraction
    }

    /// Adds `o`.
    pub fn add(&mut self, o: &Self) {
        self.primary += o.primary;
        self.shadow += o.shadow;
        self.reflection += o.reflection;
        self.refraction += o.refraction;
    }
}

/// Mirror direction `r = d − 2(d·n)n`.
#[inline]
pub fn reflect(d: Vec3, n: Vec3) -> Vec3 {
    d - 2.0 * d.dot(n) * n
}

/// The specular factor for unit normal `n`, unit direction to the light `l` and to the viewer
/// `v`, exponent `p`: Blinn–Phong `(n·h)^p` with `h = normalize(l + v)`, or Phong `(v·r)^p`
/// with `r = 2(n·l)n − l` the mirror direction of `l`; negative cosines count as 0.
pub fn specular_lobe(model: SpecularModel, n: Vec3, l: Vec3, v: Vec3, p: f32) -> f32 {
    let cos = match model {
        SpecularModel::BlinnPhong => n.dot((l + v).normalize_or_zero()),
        SpecularModel::Phong => v.dot(-reflect(l, n)),
    };
    cos.max(0.0).powf(p)
}

/// Snell refraction of unit `d` through a surface with unit normal `n` facing against `d`,
/// with `eta = n_incident / n_transmitted`; `None` on total internal reflection.
#[inline]
pub fn refract(d: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = -d.dot(n);
    let k = 1.0 - eta * eta * (1.0 - cos_i * cos_i);
    (k >= 0.0).then(|| (eta * d + (eta * cos_i - k.sqrt()) * n).normalize())
}

/// The tracer: scene + plan.
pub struct Tracer<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// The plan.
    pub plan: &'a EffectPlan,
}

impl Tracer<'_> {
    /// A fresh query context (counters zero).
    pub fn ctx(&self) -> QueryCtx {
        QueryCtx {
            force_intervals: self.plan.intervals_everywhere,
            ..QueryCtx::default()
        }
    }

    /// Closest hit over every object (the scene's top-level BVH, [`crate::scene::top`]).
    pub fn closest(&self, ray: &Ray, ctx: &mut QueryCtx) -> Option<SurfaceHit> {
        let objects = &self.scene.objects;
        self.scene.top.closest(objects, ray, ctx).map(|(_, h)| h)
    }

    /// [`Tracer::closest`] of each of `rays`: the same answers, ray for ray, each mesh
    /// walking the rays that reach it in packets ([`crate::scene::top::TopLevel::closest_batch`]).
    pub fn closest_batch(&self, rays: &[Ray], ctx: &mut QueryCtx) -> Vec<Option<SurfaceHit>> {
        let objects = &self.scene.objects;
        let hits = self.scene.top.closest_batch(objects, rays, ctx);
        hits.into_iter().map(|h| h.map(|(_, h)| h)).collect()
    }

    /// Whether anything blocks `ray` in its interval.
    pub fn occluded(&self, ray: &Ray, ctx: &mut QueryCtx) -> bool {
        self.scene.top.occluded(&self.scene.objects, ray, ctx)
    }

    /// [`Tracer::occluded`] of each of `rays`, the same answers, ray for ray (each mesh walking
    /// the rays that reach it in packets, [`crate::scene::top::TopLevel::occluded_batch`]).
    pub fn occluded_batch(&self, rays: &[Ray], ctx: &mut QueryCtx) -> Vec<bool> {
        self.scene
            .top
            .occluded_batch(&self.scene.objects, rays, ctx)
    }

    /// The shadow ray that [`Tracer::shade`] casts from `sh` towards light `li` as a plain
    /// occlusion query (a point or directional light whose shadows the plan casts from this
    /// hit, not an area light, without transmission), or `None` where it casts none or
    /// follows another path: the rays a renderer may trace as one batch per light and hand
    /// to [`Tracer::shade_known`].
    pub fn plain_shadow_ray(&self, li: usize, sh: &SurfaceHit) -> Option<Ray> {
        let light = self.scene.lights.get(li)?;
        let plain = area_centre(light).is_none()
            && !self.plan.shadow_transmission
            && self.casts_shadow(
                li,
                sh.material as usize,
                sh.shading_normal().dot(toward(light, &sh.hit).0) > 0.0,
            );
        plain.then(|| shadow_ray(light, &sh.hit))
    }

    /// Whether the plan casts shadow rays towards light `li` from a hit on material `mi` that
    /// `faces` the light (`n·l > 0` for a point or directional light; an area light's disk
    /// decides point by point, [`Tracer::area_light`]): the plan casts towards that light and
    /// evaluates the material's direct term ([`EffectPlan::direct`]).
    fn casts_shadow(&self, li: usize, mi: usize, faces: bool) -> bool {
        self.plan.shadow_rays[li] && self.plan.direct[mi] && (faces || self.plan.forced)
    }

    /// The fraction of light that reaches the end of the shadow ray `ray` (towards `light`):
    /// 0 at the first opaque surface, else the product of the `transparency` of every surface
    /// crossed (a glass sphere is crossed twice). Each segment is one shadow ray, added to
    /// `n`: at most [`MAX_SHADOW_CROSSINGS`] crossings are followed, and the segment after
    /// the last of them is still cast, so 16 crossings transmit and a surface met after them
    /// gives 0 (nothing that many panes thick lets visible light through at 8 bits); at most
    /// `MAX_SHADOW_CROSSINGS + 1` segments in all.
    fn transmission(
        &self,
        ray: &Ray,
        light: &LightKind,
        ctx: &mut QueryCtx,
        n: &mut RayCounts,
    ) -> f32 {
        let mut r = *ray;
        let mut through = 1.0f32;
        for crossed in 0..=MAX_SHADOW_CROSSINGS {
            n.shadow += 1;
            let Some(sh) = self.closest(&r, ctx) else {
                return through;
            };
            if crossed == MAX_SHADOW_CROSSINGS {
                break;
            }
            through *= self.scene.materials[sh.material as usize].transparency;
            if !(through > 0.0) {
                return 0.0;
            }
            r = match *light {
                LightKind::Point { position } => spawn_ray_to(&sh.hit, position),
                LightKind::Directional { direction } => spawn_ray(&sh.hit, -direction),
            };
        }
        0.0
    }

    /// The light an area light's disk (facing `hit`, radius `light.radius`, around `centre`)
    /// sends `hit` on the side of its shading normal `nrm`, per unit irradiance `E`: of
    /// `light.samples` fixed points of the disk (Halton positions, concentric mapping), each
    /// above the surface's tangent plane (`nrm·(p − hit) > 0`) gets a shadow ray and adds
    /// `seen × lobe(l)` (`l` the unit direction to the point; `seen` 0 or 1, or the
    /// transmission through transparent surfaces when the plan follows it); a point on or
    /// below that plane adds 0 with no ray cast (the surface itself hides it, as `n·l ≤ 0`
    /// hides a point light). The sum is divided by `light.samples`. Whether any point is above
    /// is the disk's to decide, not its centre's: a disk whose centre is below the plane can
    /// still light the point.
    #[allow(clippy::too_many_arguments)]
    fn area_light(
        &self,
        hit: &halfray_core::Hit,
        nrm: Vec3,
        centre: Vec3,
        light: &Light,
        lobe: &dyn Fn(Vec3) -> Vec3,
        ctx: &mut QueryCtx,
        n: &mut RayCounts,
    ) -> Vec3 {
        let axis = (centre - hit.point).normalize_or_zero();
        let t1 = axis.any_orthonormal_vector();
        let t2 = axis.cross(t1);
        let origins = hit.spawn_origins();
        let above = || {
            super::antialias::disk_points(light.samples)
                .map(move |(du, dv)| centre + (t1 * du + t2 * dv) * light.radius)
                .filter(move |&p| nrm.dot(p - hit.point) > 0.0)
        };
        if above().next().is_none() {
            return Vec3::ZERO;
        }
        // The objects the rays may meet, looked up once: the rays lie in the box of their
        // origins and targets.
        let scene = self.scene;
        let near = (!self.plan.shadow_transmission)
            .then(|| {
                let hull = above().fold(Aabb::new(origins[0], origins[0]), Aabb::grow);
                scene
                    .top
                    .bounded_in(&hull.grow(origins[1]), HULL_OBJECTS_MAX)
            })
            .flatten();
        let mut lit = Vec3::ZERO;
        for p in above() {
            // `spawn_ray_to(hit, p)`, bit for bit, with the hit's two origins offset once.
            let ray = shadow_segment(origins[hit.side(p - hit.point)], p);
            let seen = if self.plan.shadow_transmission {
                self.transmission(&ray, &LightKind::Point { position: p }, ctx, n)
            } else {
                n.shadow += 1;
                let occluded = match &near {
                    Some(near) => scene.top.occluded_among(&scene.objects, near, &ray, ctx),
                    None => self.occluded(&ray, ctx),
                };
                if occluded { 0.0 } else { 1.0 }
            };
            if seen > 0.0 {
                lit += seen * lobe((p - hit.point).normalize());
            }
        }
        lit / light.samples.max(1) as f32
    }

    /// Radiance along a ray (already counted by the caller).
    fn radiance(
        &self,
        ray: &Ray,
        path: &mut PathState,
        ctx: &mut QueryCtx,
        n: &mut RayCounts,
    ) -> Vec3 {
        match self.closest(ray, ctx) {
            Some(h) => self.shade_path(ray, &h, path, &[], ctx, n),
            None => self.scene.background,
        }
    }

    /// Local illumination plus the recursive terms at a primary hit, under
    /// [`PathBound::RENDER`], starting at recursion `depth` with weight 1.
    pub fn shade(
        &self,
        ray: &Ray,
        sh: &SurfaceHit,
        depth: u32,
        ctx: &mut QueryCtx,
        n: &mut RayCounts,
    ) -> Vec3 {
        self.shade_bounded(ray, sh, depth, PathBound::RENDER, ctx, n)
    }

    /// [`Tracer::shade_bounded`] at depth 0 with the plain shadow rays' answers known:
    /// `known[li]`, where given, is [`Tracer::occluded`] of [`Tracer::plain_shadow_ray`]
    /// `(li, sh)` (traced in a batch by the caller); the image is [`Tracer::shade_bounded`]'s,
    /// bit for bit, and so are the ray counts.
    pub fn shade_known(
        &self,
        ray: &Ray,
        sh: &SurfaceHit,
        bound: PathBound,
        known: &[Option<bool>],
        ctx: &mut QueryCtx,
        n: &mut RayCounts,
    ) -> Vec3 {
        let mut path = PathState::new(0, bound);
        self.shade_path(ray, sh, &mut path, known, ctx, n)
    }

    /// [`Tracer::shade`] under `bound`.
    pub fn shade_bounded(
        &self,
        ray: &Ray,
        sh: &SurfaceHit,
        depth: u32,
        bound: PathBound,
        ctx: &mut QueryCtx,
        n: &mut RayCounts,
    ) -> Vec3 {
        let mut path = PathState::new(depth, bound);
        self.shade_path(ray, sh, &mut path, &[], ctx, n)
    }

    /// Local illumination plus the recursive terms at a hit; `known[li]`, where given, is the
    /// answer of the plain shadow ray towards light `li` ([`Tracer::shade_known`]).
    fn shade_path(
        &self,
        ray: &Ray,
        sh: &SurfaceHit,
        path: &mut PathState,
        known: &[Option<bool>],
        ctx: &mut QueryCtx,
        n: &mut RayCounts,
    ) -> Vec3 {
        let scene = self.scene;
        let mi = sh.material as usize;
        let m = &scene.materials[mi];
        let hit = &sh.hit;
        let d = ray.direction.normalize();
        let v = -d;
        let nrm = sh.shading_normal();
        let mut color = m.ambient * scene.ambient;
        let specular = self.plan.specular[mi];
        // The direct term of a light of unit irradiance from unit direction `l` (an area
        // light's points).
        let direct = |l: Vec3| {
            let mut c = m.diffuse * nrm.dot(l);
            if specular {
                c += m.specular * specular_lobe(m.specular_model, nrm, l, v, m.shininess);
            }
            c
        };
        for (li, light) in scene.lights.iter().enumerate() {
            let (l, mut e) = toward(light, hit);
            let ndotl = nrm.dot(l);
            let area = area_centre(light);
            let cast = self.casts_shadow(li, mi, area.is_some() || ndotl > 0.0);
            let mut blocked = false;
            if let (true, Some(centre)) = (cast, area) {
                let lit = self.area_light(hit, nrm, centre, light, &direct, ctx, n);
                if light.cast_shadows {
                    // The disk's points, each with its own direction (a light that casts no
                    // shadows is lit as a point light at its centre, below).
                    let add = e * lit;
                    if add.is_finite() {
                        color += add;
                    }
                    continue;
                }
            } else if cast && self.plan.shadow_transmission {
                let through = self.transmission(&shadow_ray(light, hit), &light.kind, ctx, n);
                if light.cast_shadows {
                    blocked = !(through > 0.0);
                    e *= through;
                }
            } else if cast {
                n.shadow += 1;
                let occluded = match known.get(li) {
                    Some(&Some(occluded)) => occluded,
                    _ => self.occluded(&shadow_ray(light, hit), ctx),
                };
                blocked = occluded && light.cast_shadows;
            }
            if !(ndotl > 0.0) || blocked || !e.is_finite() {
                continue;
            }
            color += m.diffuse * e * ndotl;
            if specular {
                color += m.specular * e * specular_lobe(m.specular_model, nrm, l, v, m.shininess);
            }
        }
        if !path.expands(self.plan.max_depth) {
            return color;
        }
        if self.plan.reflect[mi] && (m.mirror > 0.0 || self.plan.forced) {
            let r = reflect(d, nrm);
            let cast = self.secondary(&spawn_ray(hit, r), m.mirror, path, ctx, n);
            if cast != Cast::Skipped {
                n.reflection += 1;
            }
            if let Cast::Traced(c) = cast {
                color += m.mirror * c;
            }
        }
        if self.plan.refract[mi] && (m.transparency > 0.0 || self.plan.forced) {
            let eta = if hit.front_face { 1.0 / m.ior } else { m.ior };
            let (t, refracted) = match refract(d, nrm, eta) {
                Some(t) => (t, true),
                // Total internal reflection: the transmitted share is reflected.
                None => (reflect(d, nrm), false),
            };
            let cast = self.secondary(&spawn_ray(hit, t), m.transparency, path, ctx, n);
            match (cast != Cast::Skipped, refracted) {
                (true, true) => n.refraction += 1,
                (true, false) => n.reflection += 1,
                (false, _) => {}
            }
            if let Cast::Traced(c) = cast {
                color += m.transparency * c;
            }
        }
        color
    }

    /// Casts a secondary ray with factor `k` from the node at `path` (the caller counts it):
    /// traced when the bound allows it and `k > 0`, a leaf whose result is discarded when it is
    /// a forced zero-weight ray, else skipped.
    fn secondary(
        &self,
        ray: &Ray,
        k: f32,
        path: &mut PathState,
        ctx: &mut QueryCtx,
        n: &mut RayCounts,
    ) -> Cast {
        let weight = path.weight * k;
        if path.bound.casts(path.weight, k) && path.rays_left > 0 {
            path.rays_left -= 1;
            let (depth, parent) = (path.depth, path.weight);
            path.depth += 1;
            path.weight = weight;
            let c = self.radiance(ray, path, ctx, n);
            path.depth = depth;
            path.weight = parent;
            return Cast::Traced(c);
        }
        if k == 0.0 && self.plan.forced {
            let mut leaf = PathState {
                depth: path.depth + 1,
                weight: 0.0,
                bound: path.bound,
                rays_left: 0,
            };
            let _ = self.radiance(ray, &mut leaf, ctx, n);
            return Cast::Leaf;
        }
        Cast::Skipped
    }
}

/// Towards `light` from `hit`: the unit direction to the light and the irradiance `E`
/// (`I/r²` for a point light, `I` for a directional one).
fn toward(light: &Light, hit: &halfray_core::Hit) -> (Vec3, Vec3) {
    match light.kind {
        LightKind::Point { position } => {
            let to = position - hit.point;
            (
                to.normalize_or_zero(),
                light.intensity / to.length_squared(),
            )
        }
        LightKind::Directional { direction } => (-direction, light.intensity),
    }
}

/// The shadow ray from `hit` towards `light`, by the core's robust spawn: to the light's
/// position, or along the direction to it.
fn shadow_ray(light: &Light, hit: &halfray_core::Hit) -> Ray {
    match light.kind {
        LightKind::Point { position } => spawn_ray_to(hit, position),
        LightKind::Directional { direction } => spawn_ray(hit, -direction),
    }
}

/// The centre of an area light (a point light with a disk of `radius > 0`), else `None`.
fn area_centre(light: &Light) -> Option<Vec3> {
    match light.kind {
        LightKind::Point { position } if light.radius > 0.0 => Some(position),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The two lobes on worked angles: the light at 45° on one side and the viewer mirrored
    /// (both peak, 1); the light along the normal and the viewer at 45° (Blinn–Phong sees the
    /// half vector at 22.5°: cos² 22.5° = (1 + cos 45°)/2; Phong the mirror direction at 45°:
    /// cos² 45° = ½); the viewer behind the lobe (0).
    #[test]
    fn phong_and_blinn_phong_lobes_on_worked_angles() {
        let n = Vec3::Z;
        let s = std::f32::consts::FRAC_1_SQRT_2;
        let (l, v) = (Vec3::new(s, 0.0, s), Vec3::new(-s, 0.0, s));
        for model in [SpecularModel::BlinnPhong, SpecularModel::Phong] {
            assert!(
                (specular_lobe(model, n, l, v, 7.0) - 1.0).abs() < 1e-6,
                "{model:?}"
            );
        }
        let (l, v) = (Vec3::Z, Vec3::new(s, 0.0, s));
        let blinn = specular_lobe(SpecularModel::BlinnPhong, n, l, v, 2.0);
        let phong = specular_lobe(SpecularModel::Phong, n, l, v, 2.0);
        assert!((blinn - (1.0 + s) / 2.0).abs() < 1e-6, "{blinn}");
        assert!((phong - 0.5).abs() < 1e-6, "{phong}");
        let (l, v) = (Vec3::new(s, 0.0, s), Vec3::new(s, 0.0, -s));
        assert_eq!(specular_lobe(SpecularModel::Phong, n, l, v, 3.0), 0.0);
    }
}
