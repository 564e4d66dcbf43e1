//! Hair files against forged, truncated and real input: refused without panic and without an
//! allocation the file could not justify; real samples load with plausible counts and sizes.
//!
//! The samples are reached only through `HAIRSIM_SAMPLES` (a relative value is taken from the
//! workspace root): a missing file fails when it is set; when unset those tests say they skipped.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::path::PathBuf;

use glam::Vec3;
use hairsim::export::{
    read_obj, read_ply, read_usda, write_hair, write_obj, write_ply, write_tfx, write_usda,
};
use hairsim::hairfile::{
    polyline_length, read_hair, read_tfx, HairFileError, HairModel, ReadOptions, UpAxis,
};
use hairsim_core::scenes::firmware;
use hairsim_core::{Libm, World};

/// Counts the bytes live on the current thread while tracking is on, and their peak. Per
/// thread, because the test harness runs tests in parallel in one process.
struct CountingAllocator;

thread_local! {
    static TRACKING: Cell<bool> = const { Cell::new(false) };
    static LIVE: Cell<usize> = const { Cell::new(0) };
    static PEAK: Cell<usize> = const { Cell::new(0) };
}

fn on_alloc(size: usize) {
    let _ = TRACKING.try_with(|t| {
        if t.get() {
            LIVE.with(|l| {
                let now = l.get() + size;
                l.set(now);
                PEAK.with(|p| p.set(p.get().max(now)));
            });
        }
    });
}

fn on_free(size: usize) {
    let _ = TRACKING.try_with(|t| {
        if t.get() {
            LIVE.with(|l| l.set(l.get().saturating_sub(size)));
        }
    });
}

// SAFETY: forwards to the system allocator unchanged; the bookkeeping touches only
// thread-locals with const initialisers and no destructors, which never allocate.
unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        on_alloc(layout.size());
        // SAFETY: same contract as ours.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        on_free(layout.size());
        // SAFETY: same contract as ours.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        on_alloc(layout.size());
        // SAFETY: same contract as ours.
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // New block first: during a move both are live, and the peak must see that.
        on_alloc(new_size);
        on_free(layout.size());
        // SAFETY: same contract as ours.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static ALLOCATOR: CountingAllocator = CountingAllocator;

/// Runs `f` and returns its result with the peak bytes it had allocated at once.
fn peak_of<T>(f: impl FnOnce() -> T) -> (T, usize) {
    LIVE.with(|l| l.set(0));
    PEAK.with(|p| p.set(0));
    TRACKING.with(|t| t.set(true));
    let out = f();
    TRACKING.with(|t| t.set(false));
    (out, PEAK.with(Cell::get))
}

/// The budget a read of `len` bytes may take at once: the strands themselves are at most as
/// big as the points they come from, plus per-strand `Vec` headers and the growth of the list.
fn budget(len: usize) -> usize {
    4 * len + 4096
}

fn wavy(strands: usize, points: impl Fn(usize) -> usize) -> Vec<Vec<Vec3>> {
    (0..strands)
        .map(|s| {
            let n = points(s);
            (0..n)
                .map(|i| {
                    Vec3::new(
                        0.01 * s as f32 + 0.003 * (i as f32).sin(),
                        -0.01 * i as f32,
                        0.001 * s as f32,
                    )
                })
                .collect()
        })
        .collect()
}

fn hair_bytes(strands: &[Vec<Vec3>]) -> Vec<u8> {
    let mut bytes = Vec::new();
    write_hair(&mut bytes, strands, 1e-4).unwrap();
    bytes
}

fn tfx_bytes(strands: &[Vec<Vec3>]) -> Vec<u8> {
    let mut bytes = Vec::new();
    write_tfx(&mut bytes, strands).unwrap();
    bytes
}

fn put_u32(bytes: &mut [u8], at: usize, value: u32) {
    bytes[at..at + 4].copy_from_slice(&value.to_le_bytes());
}

/// Reads forged `bytes`, asserting refusal within the allocation budget; returns the error.
fn refused(
    read: fn(&[u8], &ReadOptions) -> Result<HairModel, HairFileError>,
    bytes: &[u8],
) -> HairFileError {
    let (result, peak) = peak_of(|| read(bytes, &ReadOptions::default()));
    assert!(
        peak <= budget(bytes.len()),
        "peak {peak} bytes for a {}-byte file",
        bytes.len()
    );
    match result {
        Err(e) => {
            // Every error renders a message (and the rendering itself must not panic).
            assert!(!e.to_string().is_empty());
            e
        }
        Ok(m) => panic!("forged file accepted: {:?}", m.strands),
    }
}

#[test]
fn valid_reads_stay_within_a_small_multiple_of_the_file() {
    let uniform = hair_bytes(&wavy(50, |_| 16));
    let varied = hair_bytes(&wavy(50, |s| 2 + s % 9));
    let tfx = tfx_bytes(&wavy(50, |_| 16));
    for (bytes, read) in [
        (&uniform, read_hair as fn(&[u8], &ReadOptions) -> _),
        (&varied, read_hair),
        (&tfx, read_tfx),
    ] {
        let (model, peak) = peak_of(|| read(bytes, &ReadOptions::default()));
        assert_eq!(model.unwrap().strands.len(), 50);
        assert!(
            peak <= budget(bytes.len()),
            "peak {peak} for {} bytes",
            bytes.len()
        );
    }
}

#[test]
fn forged_hair_counts_are_refused_without_large_allocation() {
    let good = hair_bytes(&wavy(4, |_| 5));
    let varied = hair_bytes(&wavy(4, |s| 2 + s));
    let cases: Vec<(&str, Vec<u8>)> = vec![
        ("huge strand count", {
            let mut b = good.clone();
            put_u32(&mut b, 4, u32::MAX);
            b
        }),
        ("huge point count", {
            let mut b = good.clone();
            put_u32(&mut b, 8, u32::MAX);
            b
        }),
        ("huge default segments", {
            let mut b = good.clone();
            put_u32(&mut b, 16, u32::MAX);
            b
        }),
        ("huge strand count with segments", {
            let mut b = varied.clone();
            put_u32(&mut b, 4, u32::MAX);
            b
        }),
        // strands × (segments + 1) = 2^32 wraps to 0 in 32-bit arithmetic, matching 0 points.
        ("count product wrapping u32", {
            let mut b = good.clone();
            put_u32(&mut b, 4, 0x1_0000);
            put_u32(&mut b, 8, 0);
            put_u32(&mut b, 16, 0xFFFF);
            b
        }),
        ("colour array announced but absent", {
            let mut b = good.clone();
            put_u32(&mut b, 12, 0b1_0010);
            b
        }),
        ("no points array", {
            let mut b = good.clone();
            put_u32(&mut b, 12, 0b0_0001);
            b
        }),
        ("bad signature", {
            let mut b = good.clone();
            b[0] = b'X';
            b
        }),
        ("segments disagree with the point count", {
            let mut b = varied.clone();
            b[128] = 0xFF;
            b
        }),
    ];
    for (what, bytes) in &cases {
        let e = refused(read_hair, bytes);
        eprintln!("{what}: {e}");
    }
    // Past-the-end errors name the array and the byte range.
    let e = refused(read_hair, &cases[1].1);
    assert!(
        matches!(
            e,
            HairFileError::PastEnd {
                array: "points",
                start: 128,
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn forged_tfx_counts_and_offsets_are_refused_without_large_allocation() {
    let good = tfx_bytes(&wavy(3, |_| 4));
    let forge = |at: usize, value: u32| {
        let mut b = good.clone();
        put_u32(&mut b, at, value);
        b
    };
    let cases: Vec<(&str, Vec<u8>)> = vec![
        ("huge strand count", forge(4, u32::MAX)),
        ("huge vertex count", forge(8, u32::MAX)),
        ("zero vertices", forge(8, 0)),
        ("one vertex", forge(8, 1)),
        ("position offset past the end", forge(12, u32::MAX)),
        ("position offset inside the header", forge(12, 4)),
        ("strand UV past the end", forge(16, 340)),
        ("vertex colour past the end", forge(28, 200)),
        ("version 3", forge(0, 3.0f32.to_bits())),
        ("version NaN", forge(0, f32::NAN.to_bits())),
        // 2^28 strands × 16 vertices × 16 bytes = 2^36: 0 in 32-bit arithmetic.
        ("size wrapping u32", {
            let mut b = forge(4, 0x1000_0000);
            put_u32(&mut b, 8, 16);
            b
        }),
    ];
    for (what, bytes) in &cases {
        eprintln!("{what}:");
        let e = refused(read_tfx, bytes);
        eprintln!("{what}: {e}");
    }
}

#[test]
fn every_truncation_is_refused_without_panic() {
    let hair = hair_bytes(&wavy(3, |s| 2 + s));
    let tfx = tfx_bytes(&wavy(3, |_| 4));
    for cut in 0..hair.len() {
        refused(read_hair, &hair[..cut]);
    }
    for cut in 0..tfx.len() {
        refused(read_tfx, &tfx[..cut]);
    }
    // The full files read.
    assert!(read_hair(&hair, &ReadOptions::default()).is_ok());
    assert!(read_tfx(&tfx, &ReadOptions::default()).is_ok());
}

#[test]
fn nan_and_infinite_coordinates_are_refused_naming_the_strand() {
    let strands = wavy(4, |s| 3 + s);
    let hair = hair_bytes(&strands);
    // Strand 2, vertex 1, y: after header, 4 segment counts, and strands 0 (3) and 1 (4 points).
    let at = 128 + 2 * 4 + 12 * (3 + 4 + 1);
    let mut forged = hair.clone();
    forged[at + 4..at + 8].copy_from_slice(&f32::NAN.to_le_bytes());
    let e = refused(read_hair, &forged);
    assert_eq!(
        e,
        HairFileError::NonFinite {
            strand: 2,
            vertex: 1,
            offset: at
        }
    );
    assert!(e.to_string().contains("strand 2"), "{e}");

    let tfx = tfx_bytes(&wavy(3, |_| 4));
    let at = 160 + 16 * (4 + 3);
    let mut forged = tfx.clone();
    forged[at..at + 4].copy_from_slice(&f32::INFINITY.to_le_bytes());
    let e = refused(read_tfx, &forged);
    assert_eq!(
        e,
        HairFileError::NonFinite {
            strand: 1,
            vertex: 3,
            offset: at
        }
    );

    // A finite value that overflows when scaled is refused too.
    let mut big = tfx.clone();
    big[at..at + 4].copy_from_slice(&f32::MAX.to_le_bytes());
    let options = ReadOptions {
        scale: 10.0,
        ..ReadOptions::default()
    };
    assert!(matches!(
        read_tfx(&big, &options),
        Err(HairFileError::NonFinite { strand: 1, .. })
    ));
}

#[test]
fn options_scale_rotate_resample_and_thin() {
    let strands = wavy(10, |s| 3 + s);
    let hair = hair_bytes(&strands);
    let options = ReadOptions {
        scale: 2.0,
        up_axis: UpAxis::Z,
        nodes: Some(7),
        max_strands: Some(4),
        min_length: 0.0,
    };
    let model = read_hair(&hair, &options).unwrap();
    assert_eq!(model.strands.len(), 4);
    assert_eq!(model.file_strands, 10);
    // Evenly picked: strands 0, 3, 5, 8 of ten (the first at or after each multiple of 2.5).
    let picked = [0, 3, 5, 8];
    for (got, &from) in model.strands.iter().zip(&picked) {
        assert_eq!(got.len(), 7);
        let root = strands[from][0];
        // Z-up to Y-up: (x, y, z) → (x, z, −y), then scaled.
        assert_eq!(got[0], Vec3::new(root.x, root.z, -root.y) * 2.0);
        let length = polyline_length(&strands[from]) * 2.0;
        assert!((polyline_length(got) - length).abs() <= 0.02 * length);
    }
    assert!(matches!(
        read_hair(
            &hair,
            &ReadOptions {
                nodes: Some(1),
                ..ReadOptions::default()
            }
        ),
        Err(HairFileError::BadOption(_))
    ));
    assert!(matches!(
        read_hair(
            &hair,
            &ReadOptions {
                scale: f32::NAN,
                ..ReadOptions::default()
            }
        ),
        Err(HairFileError::BadOption(_))
    ));
}

/// The samples folder from `HAIRSIM_SAMPLES`, relative values taken from the workspace root;
/// `None` (after saying so) when unset.
fn samples(test: &str) -> Option<PathBuf> {
    let Some(value) = std::env::var_os("HAIRSIM_SAMPLES") else {
        eprintln!("{test}: skipped (HAIRSIM_SAMPLES is not set)");
        return None;
    };
    let path = PathBuf::from(value);
    let workspace = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    Some(if path.is_absolute() {
        path
    } else {
        workspace.join(path)
    })
}

fn sample_bytes(dir: &std::path::Path, name: &str) -> Vec<u8> {
    let path = dir.join(name);
    std::fs::read(&path).unwrap_or_else(|e| {
        panic!(
            "HAIRSIM_SAMPLES is set but {} is missing: {e}",
            path.display()
        )
    })
}

fn assert_plausible(model: &HairModel, strands: usize, points: usize, lengths: (f32, f32)) {
    assert_eq!(model.file_strands, strands);
    assert_eq!(model.strands.len(), strands);
    assert_eq!(model.points(), points);
    assert_eq!(model.dropped_short, 0);
    for (s, strand) in model.strands.iter().enumerate() {
        assert!(strand.iter().all(|p| p.is_finite()), "strand {s}");
        let length = polyline_length(strand);
        assert!(
            length >= lengths.0 && length <= lengths.1,
            "strand {s} length {length}"
        );
    }
}

#[test]
fn cem_yuksel_straight_hair_loads() {
    let Some(dir) = samples("cem_yuksel_straight_hair_loads") else {
        return;
    };
    let bytes = sample_bytes(&dir, "straight.hair");
    let options = ReadOptions {
        up_axis: UpAxis::Z,
        ..ReadOptions::default()
    };
    let (model, peak) = peak_of(|| read_hair(&bytes, &options).unwrap());
    assert!(peak <= budget(bytes.len()));
    // 10 000 strands of 16 points (the header's default of 15 segments), 55–107 units long.
    assert_plausible(&model, 10_000, 160_000, (50.0, 110.0));
    // Z-up turned Y-up: the hair hangs down, roots above tips on average.
    let (roots, tips): (f32, f32) = model
        .strands
        .iter()
        .map(|s| (s[0].y, s[15].y))
        .fold((0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1));
    assert!(roots > tips, "roots {roots} should sit above tips {tips}");
}

#[test]
fn tressfx_samples_load() {
    let Some(dir) = samples("tressfx_samples_load") else {
        return;
    };
    let sintel = read_tfx(
        &sample_bytes(&dir, "sintel_hair.tfx"),
        &ReadOptions::default(),
    )
    .unwrap();
    assert_plausible(&sintel, 228, 228 * 32, (0.01, 100.0));
    // Ratboy holds a few degenerate strands (10⁻⁵ units beside a median of 0.08): dropped.
    let options = ReadOptions {
        min_length: 1e-3,
        ..ReadOptions::default()
    };
    let ratboy = read_tfx(&sample_bytes(&dir, "Ratboy_mohawk.tfx"), &options).unwrap();
    assert_eq!(ratboy.file_strands, 2228);
    assert!(
        ratboy.dropped_short > 0 && ratboy.dropped_short < 2228 / 100,
        "{}",
        ratboy.dropped_short
    );
    assert_eq!(ratboy.points(), ratboy.strands.len() * 32);
    for strand in &ratboy.strands {
        assert!(strand.iter().all(|p| p.is_finite()));
        assert!((1e-3..1.0).contains(&polyline_length(strand)));
    }
    // Resampled to the simulator's node count, lengths keep within chord error.
    let resampled = read_tfx(
        &sample_bytes(&dir, "sintel_hair.tfx"),
        &ReadOptions {
            nodes: Some(12),
            ..ReadOptions::default()
        },
    )
    .unwrap();
    for (a, b) in resampled.strands.iter().zip(&sintel.strands) {
        assert_eq!(a.len(), 12);
        assert_eq!((a[0], a[11]), (b[0], b[31]));
        assert!(polyline_length(a) <= polyline_length(b) * (1.0 + 1e-5));
        assert!(polyline_length(a) >= 0.8 * polyline_length(b));
    }
}

#[test]
fn real_samples_survive_every_writer() {
    let Some(dir) = samples("real_samples_survive_every_writer") else {
        return;
    };
    let sintel = read_tfx(
        &sample_bytes(&dir, "sintel_hair.tfx"),
        &ReadOptions::default(),
    )
    .unwrap()
    .strands;
    let text = |write: &dyn Fn(&mut Vec<u8>)| {
        let mut b = Vec::new();
        write(&mut b);
        String::from_utf8(b).unwrap()
    };
    assert_eq!(
        read_obj(&text(&|b| write_obj(b, &sintel).unwrap())).unwrap(),
        sintel
    );
    assert_eq!(
        read_ply(&text(&|b| write_ply(b, &sintel).unwrap())).unwrap(),
        sintel
    );
    assert_eq!(
        read_usda(&text(&|b| write_usda(b, &sintel, 1e-4).unwrap())).unwrap(),
        sintel
    );
    assert_eq!(
        read_hair(&hair_bytes(&sintel), &ReadOptions::default())
            .unwrap()
            .strands,
        sintel
    );
    assert_eq!(
        read_tfx(&tfx_bytes(&sintel), &ReadOptions::default())
            .unwrap()
            .strands,
        sintel
    );
}

/// A small deterministic generator (xorshift64*), so the mutation test is repeatable.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// A poor man's fuzzer over our own seeds: header fields set to edge values, random bytes,
/// truncations. Every outcome must be a clean `Ok` or `Err` within the allocation budget.
#[test]
fn mutated_seeds_never_panic_or_over_allocate() {
    let seeds = hairsim::export::fuzz_seeds().unwrap();
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    let edge = |len: usize| {
        [
            0,
            1,
            2,
            0xFFFF,
            0x1_0000,
            0x7FFF_FFFF,
            0x8000_0000,
            u32::MAX,
            len as u32,
            len as u32 + 1,
            128,
            160,
        ]
    };
    let mut refused = 0;
    for round in 0..4000 {
        let (name, seed) = &seeds[round % seeds.len()];
        let mut bytes = seed.clone();
        let header = if name.ends_with(".tfx") { 160 } else { 128 };
        match rng.below(3) {
            0 => {
                let at = 4 * rng.below(header / 4);
                let values = edge(bytes.len());
                put_u32(&mut bytes, at, values[rng.below(values.len())]);
            }
            1 => {
                for _ in 0..1 + rng.below(4) {
                    let at = rng.below(bytes.len());
                    bytes[at] = rng.next() as u8;
                }
            }
            _ => bytes.truncate(rng.below(bytes.len())),
        }
        if name.ends_with(".hair") || name.ends_with(".tfx") {
            let read = if name.ends_with(".hair") {
                read_hair
            } else {
                read_tfx
            };
            let (result, peak) = peak_of(|| read(&bytes, &ReadOptions::default()));
            assert!(
                peak <= budget(bytes.len()),
                "{name} round {round}: peak {peak} for {} bytes",
                bytes.len()
            );
            refused += usize::from(result.is_err());
        } else if let Ok(text) = std::str::from_utf8(&bytes) {
            let result = match name.rsplit('.').next() {
                Some("obj") => read_obj(text),
                Some("ply") => read_ply(text),
                _ => read_usda(text),
            };
            refused += usize::from(result.is_err());
        }
    }
    // The mutations do bite: a good share of the files are refused.
    assert!(
        refused > 1000,
        "only {refused} of 4000 mutated files refused"
    );
}

/// The GIF writer streams: its peak memory does not grow with the number of frames.
#[test]
fn gif_writer_memory_does_not_grow_with_frames() {
    use hairsim::picture::{Camera, GifWriter, Style, View};
    let strands = wavy(20, |_| 12);
    let camera = Camera::fit_reach(&strands, &[], View::Front, 96, 96);
    let peak_for = |frames: usize| {
        peak_of(|| {
            let mut gif = GifWriter::new(std::io::sink(), camera, Style::default(), 4).unwrap();
            for k in 0..frames {
                let mut s = strands.clone();
                s.iter_mut().flatten().for_each(|p| p.x += 0.001 * k as f32);
                gif.add_frame(&s, &[]).unwrap();
            }
            gif.finish().unwrap();
        })
        .1
    };
    let (two, twenty) = (peak_for(2), peak_for(20));
    assert!(
        twenty <= two + two / 10,
        "peak {twenty} bytes for 20 frames vs {two} for 2"
    );
}

type FirmwareWorld = World<{ firmware::STRANDS }, { firmware::NODES }, Libm>;

/// A frame as `OutDir` takes it: strand positions borrowed from the world, colliders in world
/// coordinates (head-attached ones moved by the head's pose).
fn frame(world: &FirmwareWorld) -> (Vec<&[Vec3]>, Vec<hairsim_core::Shape>) {
    let strands = world.strands().iter().map(|s| s.positions()).collect();
    let head = world.head();
    let colliders = world
        .colliders()
        .iter()
        .map(|c| {
            if c.attached_to_head {
                c.shape.transformed(&head)
            } else {
                c.shape
            }
        })
        .collect();
    (strands, colliders)
}

/// The glue `hairsim run --out DIR` needs, on the firmware scene: strands straight from the
/// core's `World`, head-attached colliders moved by the head's pose, frames every 100 steps.
/// Set `HAIRSIM_PICTURES=DIR` to keep the output for a look.
#[test]
fn a_core_world_run_goes_through_out_dir() {
    use hairsim::export::{Format, OutDir, OutOptions};

    let dir = std::env::var_os("HAIRSIM_PICTURES").map_or_else(
        || std::env::temp_dir().join(format!("hairsim-run-out-{}", std::process::id())),
        PathBuf::from,
    );
    let mut world: Box<FirmwareWorld> = Box::default();
    firmware::build(&mut world).unwrap();
    let options = OutOptions {
        frame_formats: vec![Format::Obj, Format::Usda],
        ..OutOptions::default()
    };
    let mut out = OutDir::create(&dir, options).unwrap();
    for k in 0..300 {
        if k % 100 == 0 {
            let (strands, colliders) = frame(&world);
            out.frame(world.steps(), &strands, &colliders).unwrap();
        }
        world.step(&firmware::input::<Libm>(k));
    }
    let (strands, colliders) = frame(&world);
    let written = out.finish(&strands, &colliders).unwrap();
    // 3 frames × 2 formats, run.gif, final.obj, final.png.
    assert_eq!(written.len(), 3 * 2 + 3, "{written:?}");
    let text = std::fs::read_to_string(dir.join("final.obj")).unwrap();
    let back = read_obj(&text).unwrap();
    assert_eq!(back.len(), firmware::STRANDS);
    assert!(colliders.len() == 1);
    for (a, b) in back.iter().zip(&strands) {
        assert_eq!(a.as_slice(), *b);
    }
    let png = std::fs::read(dir.join("final.png")).unwrap();
    assert_eq!(&png[1..4], b"PNG");
    if std::env::var_os("HAIRSIM_PICTURES").is_none() {
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

/// What a graphics person tries first — `hairsim run model.tfx` with no options — runs every
/// real sample stably in human units: the automatic scale gives a head of
/// [`hairscene::HEAD_RADIUS`] (or hair of human length), the default DFTL scene rolls nothing
/// back, keeps segments at length and nodes out of the head.
#[test]
fn real_samples_run_in_their_default_scene() {
    use hairsim::hairscene::{HAIR_LENGTH, HEAD_RADIUS};
    use hairsim::run::{load, run, HairFileOptions, RunOptions};
    use hairsim_core::Shape;
    let Some(dir) = samples("real_samples_run_in_their_default_scene") else {
        return;
    };
    for name in ["straight.hair", "sintel_hair.tfx", "Ratboy_mohawk.tfx"] {
        let path = dir.join(name);
        let loaded = load(path.to_str().unwrap(), &HairFileOptions::default())
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        match loaded.prepared.colliders.first().map(|c| c.shape) {
            Some(Shape::Sphere { centre, radius }) => {
                // Fitted just inside the roots, and brought down to the lowest held node
                // (straight.hair 0.0807, sintel 0.0785, Ratboy 0.0814).
                assert!(
                    radius <= 0.97 * HEAD_RADIUS + 1e-4 && radius > 0.8 * HEAD_RADIUS,
                    "{name}: head {radius}"
                );
                let distance = |p: &Vec3| (*p - centre).length();
                let prepared = &loaded.prepared;
                let held = prepared
                    .strands
                    .iter()
                    .flat_map(|s| s.points.iter().take(2));
                let lowest = held.map(distance).fold(f32::INFINITY, f32::min);
                assert!(
                    lowest >= radius && lowest < radius * 1.0011,
                    "{name}: the head does not touch the scalp ({lowest} against {radius})"
                );
                // Every node starts outside it (a groom dipping into the head starts pushed out).
                let (strands, _) = prepared.start_strands::<64, Libm>().unwrap();
                let inside = strands
                    .iter()
                    .flat_map(|s| s.state.position[..s.nodes()].iter())
                    .filter(|p| distance(p) < radius * (1.0 - 1e-6))
                    .count();
                assert_eq!(inside, 0, "{name}: nodes start inside the head");
            }
            _ => {
                let mut lengths: Vec<f32> = loaded
                    .prepared
                    .strands
                    .iter()
                    .map(|s| polyline_length(&s.points))
                    .collect();
                lengths.sort_by(f32::total_cmp);
                let median = lengths[lengths.len() / 2];
                assert!(
                    (median - HAIR_LENGTH).abs() < 0.05 * HAIR_LENGTH,
                    "{name}: {median}"
                );
            }
        }
        let summary = run(
            &loaded,
            &RunOptions {
                steps: Some(300),
                ..RunOptions::default()
            },
        )
        .unwrap();
        assert!(summary.finite, "{name}");
        assert_eq!(summary.rolled_back, 0, "{name}");
        assert!(
            summary.max_stretch < 1e-3,
            "{name}: stretch {}",
            summary.max_stretch
        );
        assert!(
            summary.max_penetration < 1e-4,
            "{name}: depth {}",
            summary.max_penetration
        );
        assert!(summary.hair_file.is_some(), "{name}");
    }
}
