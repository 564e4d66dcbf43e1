//! hairsim's firmware example: a `World` in a `static`, stepped on a Cortex-M4F.
//!
//! Builds the scene `hairsim_core::scenes::firmware` (the harness runs the same scene as
//! `hairsim run firmware`), steps it, and prints the state hash over semihosting. CI runs it
//! under `qemu-system-arm -machine mps2-an386` and checks the hash equals the host's.
#![no_std]
#![no_main]

mod latency;

use core::cell::RefCell;

use cortex_m::interrupt::Mutex;
use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hprintln};
use hairsim_core::scenes::{firmware, firmware_dftl, haptic_dftl};
use hairsim_core::{Libm, Math, Real, World};

/// The math backend of this firmware: the FPU's `VSQRT` for square roots, `libm` (or, with the
/// `fast-math` feature, the core's default) for trigonometry.
///
/// IEEE 754 requires `squareRoot` to be correctly rounded, and so is `libm::sqrtf`: the two give
/// the same bits, `VSQRT` in 14 cycles instead of a software routine.
#[derive(Clone, Copy, Default)]
pub struct Vsqrt;

impl Math for Vsqrt {
    const NAME: &'static str = "vsqrt+libm";

    #[inline(always)]
    fn sqrt(x: Real) -> Real {
        let bits: u32;
        // SAFETY: VSQRT.F32 on S15, declared clobbered, so the compiler keeps nothing there
        // across it; no memory, stack or flags touched. (Rust's `sreg` operand class needs the
        // double-precision `vfp2` feature, which a Cortex-M4F does not have, hence the
        // core-register operands; a clobber needs no class.)
        unsafe {
            core::arch::asm!(
                "vmov s15, {x}",
                "vsqrt.f32 s15, s15",
                "vmov {r}, s15",
                x = in(reg) x.to_bits(),
                r = lateout(reg) bits,
                out("s15") _,
                options(pure, nomem, nostack, preserves_flags),
            );
        }
        Real::from_bits(bits)
    }

    #[inline(always)]
    fn sin_cos(x: Real) -> (Real, Real) {
        <hairsim_core::DefaultMath as Math>::sin_cos(x)
    }

    #[inline(always)]
    fn atan2(y: Real, x: Real) -> Real {
        <hairsim_core::DefaultMath as Math>::atan2(y, x)
    }
}

type FirmwareWorld = World<{ firmware::STRANDS }, { firmware::NODES }, Vsqrt>;
type DftlWorld = World<{ firmware_dftl::STRANDS }, { firmware_dftl::NODES }, Vsqrt>;

/// The worlds live in `static`s: no heap, their sizes known at link time.
static WORLD: Mutex<RefCell<FirmwareWorld>> = Mutex::new(RefCell::new(World::new()));
static DFTL_WORLD: Mutex<RefCell<DftlWorld>> = Mutex::new(RefCell::new(World::new()));

#[entry]
fn main() -> ! {
    // A profiling build runs its one latency scene only (`latency::PROFILE`).
    let code = cortex_m::interrupt::free(|cs| {
        if latency::PROFILE.is_some() {
            return debug::EXIT_SUCCESS;
        }
        let rod = run(&mut WORLD.borrow(cs).borrow_mut());
        let dftl = run_dftl(&mut DFTL_WORLD.borrow(cs).borrow_mut());
        // The same capacities as the DFTL scene's: its world, emptied.
        let haptic = run_haptic_dftl(&mut DFTL_WORLD.borrow(cs).borrow_mut());
        [rod, dftl, haptic]
            .into_iter()
            .find(|&code| code != debug::EXIT_SUCCESS)
            .unwrap_or(debug::EXIT_SUCCESS)
    });
    if code == debug::EXIT_SUCCESS {
        if let Some(mut peripherals) = cortex_m::Peripherals::take() {
            latency::start(&mut peripherals.SYST);
            latency::run();
        }
    }
    debug::exit(code);
    #[allow(clippy::empty_loop)]
    loop {}
}

fn run(world: &mut FirmwareWorld) -> debug::ExitStatus {
    if !sqrt_matches_libm() {
        hprintln!("error: VSQRT and libm::sqrtf disagree");
        return debug::EXIT_FAILURE;
    }
    let result = firmware::run(world, firmware::STEPS);
    print_result("firmware", world, result)
}

fn run_dftl(world: &mut DftlWorld) -> debug::ExitStatus {
    let result = firmware_dftl::run(world, firmware_dftl::STEPS);
    print_result("firmware-dftl", world, result)
}

fn run_haptic_dftl(world: &mut DftlWorld) -> debug::ExitStatus {
    *world = World::new();
    let result = haptic_dftl::run(world, haptic_dftl::STEPS);
    print_result("haptic-dftl", world, result)
}

/// Prints `scene NAME steps … state_hash 0x…` (the line CI compares with the host) and says
/// whether the run succeeded: built, and finite at the end.
fn print_result<const S: usize, const N: usize>(
    name: &str,
    world: &World<S, N, Vsqrt>,
    result: Result<u64, hairsim_core::Error>,
) -> debug::ExitStatus {
    match result {
        Ok(hash) => {
            let finite = world.strands().iter().all(|s| s.is_finite());
            hprintln!(
                "scene {} steps {} strands {} finite {} grabs held {} state_hash 0x{:016x}",
                name,
                world.steps(),
                world.strands().len(),
                finite,
                world
                    .grabs()
                    .iter()
                    .filter(|g| g.status == hairsim_core::GrabStatus::Held)
                    .count(),
                hash
            );
            if finite {
                debug::EXIT_SUCCESS
            } else {
                debug::EXIT_FAILURE
            }
        }
        Err(e) => {
            hprintln!("error: building the {} scene: {}", name, e);
            debug::EXIT_FAILURE
        }
    }
}

/// The backend's promise, checked on the target itself: `VSQRT` gives `libm`'s bits.
fn sqrt_matches_libm() -> bool {
    let mut x: f32 = 1.0e-20;
    while x < 1.0e20 {
        if Vsqrt::sqrt(x).to_bits() != Libm::sqrt(x).to_bits() {
            return false;
        }
        x *= 1.013;
    }
    true
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    hprintln!("panic: {}", info);
    debug::exit(debug::EXIT_FAILURE);
    #[allow(clippy::empty_loop)]
    loop {}
}
