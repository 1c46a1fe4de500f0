//! The renderer: `halfray render SCENE.toml -o OUT.png`.
//!
//! One sample per pixel through the pixel centre, Whitted shading ([`trace`]) under an effect
//! plan ([`plan`]), all cores through rayon, an indicatif progress bar on a terminal, and an
//! 8-bit sRGB RGBA PNG written atomically ([`output`]). Every render ends with a summary line
//! of rays cast per kind, time and Mrays/s.

pub mod antialias;
pub mod bound;
pub mod budget;
pub mod gamma;
pub mod output;
pub mod plan;
pub mod trace;

use crate::console::print_out;
use crate::error::{Error, Result};
use crate::limits::check_memory;
use crate::outputs::{Named, refuse_inputs, reserve_outputs, write_together};
use crate::scene::geom::{QueryCtx, SurfaceHit};
use crate::scene::{self, Scene};
use bound::PathBound;
use glam::{Vec3, Vec4};
use indicatif::{ParallelProgressIterator, ProgressBar, ProgressDrawTarget, ProgressStyle};
use plan::EffectPlan;
use rayon::prelude::*;
use std::io::IsTerminal;
use std::path::PathBuf;
use std::time::Instant;
use trace::{RayCounts, Tracer};

/// What each pixel shows.
#[derive(clap::ValueEnum, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Mode {
    /// Whitted shading (sRGB).
    #[default]
    Color,
    /// Distance from the eye along the primary ray, normalised to the nearest (white) and
    /// farthest (black) hit of the image.
    Depth,
    /// World-space outward geometric normal as `n·½ + ½`.
    Normal,
    /// Triangle barycentrics `(b0, b1, b2)` as RGB (grey on non-triangle primitives).
    Barycentric,
    /// BVH nodes visited by the primary ray, on a fixed logarithmic ramp (1023 nodes = red).
    Heatmap,
}

impl Mode {
    /// The transfer function between the pixel values and the stored 8-bit values: `transfer`
    /// in colour mode (linear radiance), `None` in the debug modes (a value `v` in `[0, 1]` is
    /// stored as `v · 255`, rounded).
    pub fn transfer(self, transfer: gamma::Transfer) -> Option<gamma::Transfer> {
        (self == Self::Color).then_some(transfer)
    }
}

/// `halfray render SCENE.toml -o OUT.png`.
#[derive(clap::Args, Debug, Clone)]
pub struct RenderArgs {
    /// Scene file (TOML; format in scenes/README.md).
    pub scene: PathBuf,
    /// Output PNG (written atomically).
    #[arg(short, long)]
    pub output: PathBuf,
    /// What to render.
    #[arg(long, value_enum, default_value_t = Mode::Color)]
    pub mode: Mode,
    /// Print the effect plan before rendering: what the render simulates in its `--mode`
    /// (outside colour, one ray per pixel), and the worst-case work.
    #[arg(long)]
    pub explain: bool,
    /// Write ray counts per kind, the time and the effect plan as JSON (keys primary, shadow,
    /// reflection, refraction, seconds, plan).
    #[arg(long, value_name = "FILE")]
    pub stats_json: Option<PathBuf>,
    /// Composite the render (source) with this image (destination) by `--op` (same size as
    /// the render). In colour mode in linear radiance, the image decoded by `--gamma`; in the
    /// debug modes on the image's stored values (not decoded), as the debug values are written.
    #[arg(long, value_name = "IMG.png")]
    pub background: Option<PathBuf>,
    /// Most samples per pixel (colour mode): one ray through each pixel's centre, then up to
    /// N − 1 more at fixed sub-pixel positions only where a pixel differs from a neighbour
    /// (edges, shadow boundaries, mirror rims), averaged. Deterministic. Default: the scene's
    /// `samples` (1 when it sets none).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=scene::MAX_SAMPLES as i64))]
    pub samples: Option<u32>,
    /// Output transfer function: `srgb`, or a display gamma `γ` (stored = linear^(1/γ); find
    /// yours with `halfray gamma --chart`). Also decodes `--background` (colour mode).
    #[arg(long, default_value = "srgb", value_name = "srgb|GAMMA")]
    pub gamma: gamma::Transfer,
    /// The Porter–Duff operator for `--background`.
    #[arg(
        long,
        value_enum,
        default_value_t,
        requires = "background",
        ignore_case = true
    )]
    pub op: crate::composite::Operator,
    /// Write the pixels where no object is hit with alpha 0 (colour mode; for compositing
    /// elsewhere). By default the scene's background colour is written opaque.
    #[arg(long, conflicts_with = "background")]
    pub transparent_background: bool,
    /// Turn every effect on (for comparison with the plan): the picture is the same in every
    /// mode but `heatmap`, which shows the work done (forced, every solid is evaluated through
    /// the CSG interval code and its BVH nodes counted).
    #[arg(long)]
    pub force_all_effects: bool,
    /// Override the scene's image width.
    #[arg(long)]
    pub width: Option<u32>,
    /// Override the scene's image height.
    #[arg(long)]
    pub height: Option<u32>,
    /// Replace outputs that are read-only or hard-linked (keeping their mode).
    #[arg(long)]
    pub force: bool,
    /// Render even when the worst-case work is over the budget
    /// (`render::budget::MAX_WORST_CASE_WORK`; `--explain` prints the estimate).
    #[arg(long)]
    pub allow_long: bool,
    /// No progress bar and no settings line (the summary line is still printed).
    #[arg(short, long)]
    pub quiet: bool,
    /// Trace each primary and shadow ray alone instead of each row's as one batch (the same
    /// image; for comparing their speed).
    #[arg(long)]
    pub single_rays: bool,
}

/// Render settings of the library entry point.
#[derive(Clone, Debug, Default)]
pub struct RenderOptions {
    /// Mode.
    pub mode: Mode,
    /// `--force-all-effects`.
    pub force_all: bool,
    /// Show a progress bar (only drawn when stderr is a terminal).
    pub progress: bool,
    /// How far each pixel's ray tree is followed.
    pub bound: PathBound,
    /// Most samples per pixel (colour mode; 0 and 1 mean one): adaptive anti-aliasing, see
    /// [`antialias`].
    pub samples: u32,
    /// Trace each primary and shadow ray alone instead of a row's as one batch (the same
    /// image; the heat map and depth of field always do).
    pub single_rays: bool,
}

/// A finished render.
#[derive(Clone, Debug)]
pub struct Rendered {
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
    /// Per pixel, row-major from the top: linear RGB radiance (colour mode) or the debug
    /// value in `[0, 1]`, and coverage alpha (1 hit, 0 miss).
    pub pixels: Vec<Vec4>,
    /// BVH nodes visited per pixel by the primary ray; counted where each ray is traced alone
    /// (the heat map, depth of field, [`RenderOptions::single_rays`]), 0 in a batched row.
    pub nodes: Vec<u64>,
    /// Rays cast per kind.
    pub counts: RayCounts,
    /// Wall-clock seconds of the render loop.
    pub seconds: f64,
    /// The plan used.
    pub plan: EffectPlan,
}

impl Rendered {
    /// Pixel `(i, j)`.
    pub fn pixel(&self, i: u32, j: u32) -> Vec4 {
        self.pixels[(j * self.width + i) as usize]
    }

    /// Number of covered pixels.
    pub fn coverage(&self) -> usize {
        self.pixels.iter().filter(|p| p.w > 0.0).count()
    }

    /// 8-bit RGBA: encoded by `transfer` in colour mode, the value as is in debug modes; the
    /// buffer is allocated at its exact size, 4 bytes a pixel.
    pub fn to_rgba8(&self, mode: Mode, transfer: gamma::Transfer) -> Vec<u8> {
        let transfer = mode.transfer(transfer);
        let enc = |x: f32| crate::png::to_u8(transfer.map_or(x, |t| t.encode(x)));
        let mut rgba = Vec::with_capacity(4 * self.pixels.len());
        for p in &self.pixels {
            rgba.extend([enc(p.x), enc(p.y), enc(p.z), crate::png::to_u8(p.w)]);
        }
        rgba
    }

    /// Makes every pixel opaque: the render over the `background` colour (linear), so a pixel
    /// an edge covers in part blends the two.
    pub fn make_opaque(&mut self, background: Vec3) {
        let bg = background.extend(1.0);
        for p in &mut self.pixels {
            *p = crate::composite::Operator::Over.apply(*p, bg);
        }
    }

    /// Composites the render (source) with a background (destination; straight RGBA in the
    /// pixels' space, [`Mode::transfer`]: linear in colour mode; same size) by `op`, for 8-bit
    /// output ([`crate::composite::Operator::apply_8bit`]: a pixel whose alpha rounds to 0 is
    /// `Vec4::ZERO`).
    pub fn composite(&mut self, background: &[Vec4], op: crate::composite::Operator) {
        for (p, b) in self.pixels.iter_mut().zip(background) {
            *p = op.apply_8bit(*p, *b);
        }
    }
}

/// Per-pixel record before the debug-mode mapping.
#[derive(Clone, Copy, Default)]
struct PixelOut {
    value: Vec3,
    alpha: f32,
    depth: f32,
    nodes: u64,
}

/// Renders a scene (library entry point; the CLI adds files and printing).
pub fn render(scene: &Scene, opts: &RenderOptions) -> Rendered {
    let plan = EffectPlan::derive(scene, opts.force_all);
    let tracer = Tracer { scene, plan: &plan };
    let (w, h) = (scene.camera.width, scene.camera.height);
    let bar = if opts.progress && std::io::stderr().is_terminal() {
        let b = ProgressBar::with_draw_target(Some(u64::from(h)), ProgressDrawTarget::stderr());
        if let Ok(style) =
            ProgressStyle::with_template("{elapsed_precise} [{bar:40}] {pos}/{len} rows {eta}")
        {
            b.set_style(style.progress_chars("=> "));
        }
        b
    } else {
        ProgressBar::hidden()
    };
    // A row's primary rays as one batch, unless each pixel needs its own count of nodes (the
    // heat map) or several rays (depth of field).
    let through_lens = scene.camera.lens.is_some() && opts.mode == Mode::Color;
    let batched = !opts.single_rays && opts.mode != Mode::Heatmap && !through_lens;
    let start = Instant::now();
    // Each row is written into the one image buffer as it is finished (a row's own records
    // live only while it is traced: [`render_bytes`]).
    let mut px = vec![PixelOut::default(); w as usize * h as usize];
    let mut counts = px
        .par_chunks_mut(w as usize)
        .enumerate()
        .progress_with(bar.clone())
        .map(|(j, out)| {
            let j = j as u32;
            let mut counts = RayCounts::default();
            if batched {
                out.copy_from_slice(&row_batched(&tracer, opts, j, &mut counts));
            } else {
                for (i, p) in (0..w).zip(out) {
                    *p = pixel(&tracer, opts, i, j, &mut counts);
                }
            }
            counts
        })
        .reduce(RayCounts::default, |mut a, b| {
            a.add(&b);
            a
        });
    let mut seconds = start.elapsed().as_secs_f64();
    bar.finish_and_clear();

    // Depth of field samples every pixel already.
    if opts.samples > 1 && opts.mode == Mode::Color && scene.camera.lens.is_none() {
        let start = Instant::now();
        counts.add(&antialias::refine(&mut px, w, opts.samples, |x, y, c| {
            sample(&tracer, opts, scene.camera.ray_at(x, y), c)
        }));
        seconds += start.elapsed().as_secs_f64();
    }
    let (mut dmin, mut dmax) = (f32::INFINITY, f32::NEG_INFINITY);
    for p in px.iter().filter(|p| p.alpha > 0.0) {
        dmin = dmin.min(p.depth);
        dmax = dmax.max(p.depth);
    }
    let pixels = px
        .iter()
        .map(|p| {
            let v = match opts.mode {
                Mode::Depth if p.alpha > 0.0 => {
                    let span = dmax - dmin;
                    Vec3::splat(if span > 0.0 {
                        1.0 - (p.depth - dmin) / span
                    } else {
                        1.0
                    })
                }
                Mode::Heatmap => output::heat(p.nodes),
                _ => p.value,
            };
            v.extend(p.alpha)
        })
        .collect();
    Rendered {
        width: w,
        height: h,
        pixels,
        nodes: px.iter().map(|p| p.nodes).collect(),
        counts,
        seconds,
        plan,
    }
}

fn pixel(
    tracer: &Tracer<'_>,
    opts: &RenderOptions,
    i: u32,
    j: u32,
    counts: &mut RayCounts,
) -> PixelOut {
    let camera = &tracer.scene.camera;
    let (x, y) = (i as f32, j as f32);
    match camera.lens {
        // Depth of field: every pixel through `samples` lens and sub-pixel positions.
        Some(lens) if opts.mode == Mode::Color => antialias::mean((0..lens.samples).map(|k| {
            let ((dx, dy), (lu, lv)) = (antialias::offset(k), antialias::lens_offset(k));
            sample(
                tracer,
                opts,
                camera.ray_through_lens(x + dx, y + dy, lu, lv),
                counts,
            )
        })),
        _ => sample(tracer, opts, camera.ray_at(x + 0.5, y + 0.5), counts),
    }
}

/// Row `j`'s pixels, one primary ray through each centre, traced as one batch
/// ([`Tracer::closest_batch`]): the pixels [`pixel`] gives without a lens, but no nodes counted.
// Out of line: one call a row, and a symbol for profilers (`--toggle-collect`).
#[inline(never)]
fn row_batched(
    tracer: &Tracer<'_>,
    opts: &RenderOptions,
    j: u32,
    counts: &mut RayCounts,
) -> Vec<PixelOut> {
    let camera = &tracer.scene.camera;
    let y = j as f32;
    let rays: Vec<halfray_core::Ray> = (0..camera.width)
        .map(|i| camera.ray_at(i as f32 + 0.5, y + 0.5))
        .collect();
    let mut ctx = tracer.ctx();
    let hits = tracer.closest_batch(&rays, &mut ctx);
    // The row's plain shadow rays as one batch per light, where the top level batches them
    // (the scene's one bounded object is a mesh); elsewhere the shading traces them alone.
    let scene = tracer.scene;
    let batched = scene.top.occlusion_batched(&scene.objects).is_some();
    let known = if opts.mode == Mode::Color && batched {
        shadows_batched(tracer, &hits, &mut ctx)
    } else {
        Vec::new()
    };
    let lights = scene.lights.len();
    rays.iter()
        .zip(hits)
        .enumerate()
        .map(|(i, (ray, hit))| {
            counts.primary += 1;
            let known = known.get(i * lights..(i + 1) * lights).unwrap_or(&[]);
            shade_primary(tracer, opts, ray, hit, 0, known, counts)
        })
        .collect()
}

/// The answers of the plain shadow rays ([`Tracer::plain_shadow_ray`]) from a row's primary
/// `hits`, traced as one batch per light ([`Tracer::occluded_batch`]: shadow rays towards a
/// point light walked in packets): entry `i · L + li` (`L` lights) is pixel `i`'s answer
/// towards light `li`, `None` where that pixel casts no plain shadow ray towards it.
fn shadows_batched(
    tracer: &Tracer<'_>,
    hits: &[Option<SurfaceHit>],
    ctx: &mut QueryCtx,
) -> Vec<Option<bool>> {
    let lights = tracer.scene.lights.len();
    let mut known = vec![None; hits.len() * lights];
    let (mut rays, mut pixels) = (Vec::new(), Vec::new());
    for li in 0..lights {
        rays.clear();
        pixels.clear();
        for (i, sh) in hits.iter().enumerate() {
            if let Some(ray) = sh.as_ref().and_then(|sh| tracer.plain_shadow_ray(li, sh)) {
                rays.push(ray);
                pixels.push(i);
            }
        }
        for (&i, blocked) in pixels.iter().zip(tracer.occluded_batch(&rays, ctx)) {
            known[i * lights + li] = Some(blocked);
        }
    }
    known
}

/// One primary ray.
fn sample(
    tracer: &Tracer<'_>,
    opts: &RenderOptions,
    ray: halfray_core::Ray,
    counts: &mut RayCounts,
) -> PixelOut {
    counts.primary += 1;
    let mut ctx = tracer.ctx();
    let hit = tracer.closest(&ray, &mut ctx);
    shade_primary(
        tracer,
        opts,
        &ray,
        hit,
        ctx.stats.nodes_visited,
        &[],
        counts,
    )
}

/// The pixel of the primary ray `ray` whose closest hit is `hit`, after `nodes` node visits;
/// `known`: its plain shadow rays' answers where traced already ([`Tracer::shade_known`]).
fn shade_primary(
    tracer: &Tracer<'_>,
    opts: &RenderOptions,
    ray: &halfray_core::Ray,
    hit: Option<SurfaceHit>,
    nodes: u64,
    known: &[Option<bool>],
    counts: &mut RayCounts,
) -> PixelOut {
    let mode = opts.mode;
    let mut ctx = tracer.ctx();
    let Some(sh) = hit else {
        return PixelOut {
            value: if mode == Mode::Color {
                tracer.scene.background
            } else {
                Vec3::ZERO
            },
            nodes,
            ..PixelOut::default()
        };
    };
    let value = match mode {
        Mode::Color => tracer.shade_known(ray, &sh, opts.bound, known, &mut ctx, counts),
        Mode::Normal => sh.hit.normal * 0.5 + 0.5,
        Mode::Barycentric => sh.bary.unwrap_or(Vec3::splat(0.5)),
        Mode::Depth | Mode::Heatmap => Vec3::ZERO,
    };
    PixelOut {
        value,
        alpha: 1.0,
        depth: sh.hit.t * ray.direction.length(),
        nodes,
    }
}

/// Most bytes a thread's row holds while it is traced, per pixel of the row: its rays, hits,
/// shadow answers and records (about 250 bytes a pixel, from the sizes of `Ray`, `SurfaceHit`
/// and [`PixelOut`]), with a margin: a row is small beside the image, so the allowance is
/// generous rather than exact.
const ROW_SCRATCH_BYTES_PER_PIXEL: u64 = 1024;

/// Most bytes of the PNG encoder's zlib stream per byte of filtered image data (4 bytes a pixel
/// and a filter byte a row), ×64: deflate stores a block that does not compress as it is, with
/// 5 bytes of header per block of at most 65 535 bytes (under 1/10 000), so 65/64 is a margin,
/// not an estimate.
const PNG_STREAM_BOUND: (u64, u64) = (65, 64);

/// Memory a `w`×`h` render by `halfray render` holds at its peak, in bytes (`None` on
/// overflow), on `threads` threads: an upper bound, the largest of its phases, each counted
/// buffer by buffer. Tracing: the image's per-pixel records (`PixelOut`), the 1-byte mask of
/// the pixels anti-aliasing refines, and each thread's row scratch
/// (`ROW_SCRATCH_BYTES_PER_PIXEL`); mapping: the records, the final pixels (`Vec4`) and the
/// node counts (`u64`); writing: the pixels and node counts, the 8-bit RGBA copy (4 bytes a
/// pixel) and the PNG, counted as five times its zlib stream's bound (`PNG_STREAM_BOUND`):
/// the encoder's stream and the file's bytes each grow by doubling, so each holds at most twice
/// its length and a growing one three times for the moment of its copy. The decoded
/// `background` (a `Vec4` a pixel) is held through tracing and mapping.
pub fn render_bytes(w: u32, h: u32, background: bool, threads: usize) -> Option<u64> {
    let size = |t: usize| t as u64;
    let pixels = u64::from(w).checked_mul(u64::from(h))?;
    let per = |bytes: u64| pixels.checked_mul(bytes);
    let bg = if background {
        size(std::mem::size_of::<Vec4>())
    } else {
        0
    };
    let record = size(std::mem::size_of::<PixelOut>());
    let scratch = u64::from(w)
        .checked_mul(ROW_SCRATCH_BYTES_PER_PIXEL)?
        .checked_mul(threads.max(1) as u64)?;
    let final_pixels = size(std::mem::size_of::<Vec4>()) + size(std::mem::size_of::<u64>());
    let tracing = per(record + 1 + bg)?.checked_add(scratch)?;
    let mapping = per(record + final_pixels + bg)?;
    let filtered = per(4)?.checked_add(u64::from(h))?;
    let stream = filtered.checked_mul(PNG_STREAM_BOUND.0)? / PNG_STREAM_BOUND.1 + 1024;
    let writing = per(final_pixels + 4)?.checked_add(stream.checked_mul(5)?)?;
    Some(tracing.max(mapping).max(writing))
}

/// The JSON written by `--stats-json`.
#[derive(serde::Serialize)]
struct StatsJson {
    primary: u64,
    shadow: u64,
    reflection: u64,
    refraction: u64,
    seconds: f64,
    /// Which effects the renderer simulated ([`plan::PlanFlags`]).
    plan: plan::PlanFlags,
}

/// The summary line printed after every render.
pub fn summary(r: &Rendered) -> String {
    let c = &r.counts;
    let total = c.total();
    let mrays = crate::timing::mrays_per_second(total, r.seconds);
    format!(
        "rays: primary {} shadow {} reflection {} refraction {} (total {total}) in {:.3} s, {mrays:.2} Mrays/s",
        c.primary, c.shadow, c.reflection, c.refraction, r.seconds
    )
}

/// Runs `halfray render`: checks the options and reserves every output, loads the scene
/// (refusing outputs that are among its files), renders, writes the PNG and `--stats-json`
/// together (both or neither, see [`write_together`]), and prints the summary last (a closed
/// stdout loses nothing).
pub fn run(args: &RenderArgs) -> Result<()> {
    for (v, name) in [(args.width, "--width"), (args.height, "--height")] {
        if v.is_some_and(|x| x == 0 || x > scene::MAX_IMAGE_SIDE) {
            return Err(Error::Usage(format!(
                "{name} must be in 1..={}",
                scene::MAX_IMAGE_SIDE
            )));
        }
    }
    let mut outputs = vec![Named::new("-o", &args.output)];
    if let Some(p) = &args.stats_json {
        outputs.push(Named::new("--stats-json", p));
    }
    let mut inputs = vec![Named::new("scene", &args.scene)];
    if let Some(p) = &args.background {
        inputs.push(Named::new("--background", p));
    }
    let reserved = reserve_outputs(&outputs, &inputs, args.force)?;
    let mut scene = scene::load(&args.scene)?;
    let mesh_inputs: Vec<Named<'_>> = scene
        .mesh_files
        .iter()
        .map(|p| Named::new("mesh file", p))
        .collect();
    refuse_inputs(&reserved, &outputs, &mesh_inputs)?;
    // After the input checks: an output that is an input is reported as such.
    crate::png::check_png_name(Named::new("-o", &args.output))?;
    if let Some(x) = args.width {
        scene.camera.width = x;
    }
    if let Some(y) = args.height {
        scene.camera.height = y;
    }
    let (w, h) = (scene.camera.width, scene.camera.height);
    let bytes = render_bytes(
        w,
        h,
        args.background.is_some(),
        rayon::current_num_threads(),
    );
    if args.width.is_none() && args.height.is_none() {
        // The size is the scene file's: an input error at its `camera.width`.
        check_memory(&format!("an image of {w}×{h} pixels"), bytes)
            .map_err(|e| Error::input(scene.size_at.clone(), e.to_string()))?;
    } else {
        check_memory(
            &format!("an image of {w}×{h} pixels (--width/--height)"),
            bytes,
        )?;
    }
    let mut background = match &args.background {
        Some(p) => Some(output::read_background(
            p,
            w,
            h,
            args.mode.transfer(args.gamma),
        )?),
        None => None,
    };
    let opts = RenderOptions {
        samples: args.samples.unwrap_or(scene.samples),
        mode: args.mode,
        force_all: args.force_all_effects,
        progress: !args.quiet,
        bound: PathBound::RENDER,
        single_rays: args.single_rays,
    };
    let plan = EffectPlan::derive(&scene, opts.force_all);
    let estimate = budget::Estimate::of(&scene, &plan, opts.mode, opts.samples);
    if args.explain {
        let threads = rayon::current_num_threads();
        let text = plan.explain(&scene, opts.mode, opts.samples);
        print_out(&(text + &estimate.explain(threads)))?;
    }
    if estimate.over_budget() && !args.allow_long {
        return Err(Error::Usage(format!(
            "{}: the worst case is {:.3e} rays × {} coincident objects, over the budget of {:.0e} \
             (render::budget::MAX_WORST_CASE_WORK; at most about {} on {} threads); \
             --explain shows where they come from, --allow-long renders anyway",
            crate::text::path(&args.scene),
            estimate.rays(),
            estimate.coincident.max(1),
            budget::MAX_WORST_CASE_WORK,
            budget::duration(estimate.seconds(rayon::current_num_threads())),
            rayon::current_num_threads()
        )));
    }
    if !args.quiet {
        crate::note!(
            "rendering {} ({w}×{h}, mode {:?}, {} threads)",
            crate::text::path(&args.scene),
            args.mode,
            rayon::current_num_threads()
        );
    }
    let mut out = render(&scene, &opts);
    if let Some(bg) = background.take() {
        // Freed before the image is written ([`render_bytes`]).
        out.composite(&bg, args.op);
    } else if args.mode == Mode::Color && !args.transparent_background {
        out.make_opaque(scene.background);
    }
    let mut reserved = reserved.into_iter();
    let png = reserved.next().expect("-o is reserved first");
    let mut files = Vec::new();
    if let Some(stats) = reserved.next() {
        let c = &out.counts;
        let json = serde_json::to_string_pretty(&StatsJson {
            primary: c.primary,
            shadow: c.shadow,
            reflection: c.reflection,
            refraction: c.refraction,
            seconds: out.seconds,
            plan: plan.flags(&scene, opts.mode, opts.samples),
        })
        .map_err(|e| Error::encode("the stats JSON", e))?;
        files.push((stats, format!("{json}\n").into_bytes()));
    }
    let mut bytes = Vec::new();
    crate::png::encode_png(&mut bytes, w, h, &out.to_rgba8(args.mode, args.gamma))
        .map_err(|e| Error::encode("the PNG image", e))?;
    files.insert(0, (png, bytes));
    // The image and its statistics: both or neither.
    write_together(files)?;
    if !args.quiet {
        crate::note!("wrote {}", crate::text::path(&args.output));
    }
    print_out(&format!("{}\n", summary(&out)))
}
