//! The memory `halfray render` holds: its peak, measured by counting every allocation of the
//! process, is at most `render_bytes`, the estimate its 4 GiB check refuses images by. One test
//! in this file: the counter is the whole process's.

use halfray::render::{RenderArgs, render_bytes, run};
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicU64, Ordering};

/// The system allocator, counting the bytes allocated now and their peak.
struct Counting;

static NOW: AtomicU64 = AtomicU64::new(0);
static PEAK: AtomicU64 = AtomicU64::new(0);

fn grow(bytes: usize) {
    let now = NOW.fetch_add(bytes as u64, Ordering::SeqCst) + bytes as u64;
    PEAK.fetch_max(now, Ordering::SeqCst);
}

fn shrink(bytes: usize) {
    NOW.fetch_sub(bytes as u64, Ordering::SeqCst);
}

// SAFETY: every call is forwarded to `System` unchanged; only counters are added.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        grow(layout.size());
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        grow(layout.size());
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) };
        shrink(layout.size());
    }
    /// Counted as a new block beside the old one until it is freed (a copy).
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        grow(new_size);
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        shrink(layout.size());
        p
    }
}

#[global_allocator]
static COUNTING: Counting = Counting;

#[derive(clap::Parser)]
struct Cli {
    #[command(flatten)]
    args: RenderArgs,
}

/// `halfray render` of a sphere on a floor at 400×300, with anti-aliasing (4 samples), then with
/// that image as its `--background`: the peak of each run, above what was allocated before it,
/// is at most the estimate plus the loaded scene (which the estimate of the image's buffers does
/// not count; measured by loading it alone); the image dominates it (over half of the estimate
/// is used).
#[test]
fn a_renders_peak_memory_is_at_most_its_estimate() {
    use clap::Parser as _;
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("s.toml");
    std::fs::write(
        &scene,
        r#"[camera]
eye = [0, 2, 6]
look_at = [0, 0.5, 0]
fov = 50
width = 400
height = 300

[[light]]
type = "point"
position = [2, 5, 3]
intensity = 30

[material.m]
diffuse = [0.7, 0.7, 0.7]
specular = [0.3, 0.3, 0.3]

[[object]]
type = "plane"
point = [0, 0, 0]
normal = [0, 1, 0]
material = "m"

[[object]]
type = "sphere"
center = [0, 0.8, 0]
radius = 0.8
material = "m"
"#,
    )
    .unwrap();
    let first = dir.path().join("a.png");
    let second = dir.path().join("b.png");
    let (s, a, b) = (
        scene.to_str().unwrap(),
        first.to_str().unwrap(),
        second.to_str().unwrap(),
    );
    rayon::ThreadPoolBuilder::new().build_global().ok();
    let threads = rayon::current_num_threads();
    let scene_bytes = {
        let before = NOW.load(Ordering::SeqCst);
        PEAK.store(before, Ordering::SeqCst);
        drop(halfray::scene::load(&scene).unwrap());
        PEAK.load(Ordering::SeqCst) - before
    };
    for (argv, background) in [
        (vec!["render", s, "-o", a, "-q", "--samples", "4"], false),
        (vec!["render", s, "-o", b, "-q", "--background", a], true),
    ] {
        let cli = Cli::try_parse_from(&argv).unwrap();
        let before = NOW.load(Ordering::SeqCst);
        PEAK.store(before, Ordering::SeqCst);
        run(&cli.args).unwrap();
        let peak = PEAK.load(Ordering::SeqCst) - before;
        let estimate = render_bytes(400, 300, background, threads).unwrap();
        assert!(
            peak <= estimate + scene_bytes && 2 * peak > estimate,
            "{argv:?}: peak {peak} bytes, estimate {estimate} + the scene's {scene_bytes}"
        );
    }
}
