//! The `lambert` command line: parses, calls the library, prints.

use std::process::ExitCode;

mod cli;
mod plot;
mod progress_bar;
mod view;

/// Which signal ctrlc's handler was called for: ctrlc calls one handler
/// for SIGINT, SIGTERM and SIGHUP and does not say which.
#[cfg(unix)]
mod signals {
    use std::sync::atomic::{AtomicI32, AtomicUsize, Ordering};

    static LAST: AtomicI32 = AtomicI32::new(libc::SIGINT);
    /// ctrlc's own handler, which `note` hands each signal on to.
    static CTRLC: AtomicUsize = AtomicUsize::new(0);

    extern "C" fn note(signal: libc::c_int) {
        // Async-signal-safe: atomics, then ctrlc's handler (a semaphore post).
        LAST.store(signal, Ordering::SeqCst);
        let handler = CTRLC.load(Ordering::SeqCst);
        if handler > libc::SIG_IGN {
            // SAFETY: a plain handler's address, as sigaction returned it.
            let ctrlc: extern "C" fn(libc::c_int) = unsafe { std::mem::transmute(handler) };
            ctrlc(signal);
        }
    }

    /// Puts `note` in front of the handler ctrlc installed.
    pub fn note_which() {
        for signal in [libc::SIGINT, libc::SIGTERM, libc::SIGHUP] {
            // SAFETY: sigaction with valid pointers; `note` keeps ctrlc's
            // flags and mask, and is installed only over a plain handler.
            unsafe {
                let mut action: libc::sigaction = std::mem::zeroed();
                if libc::sigaction(signal, std::ptr::null(), &mut action) != 0
                    || action.sa_flags & libc::SA_SIGINFO != 0
                    || action.sa_sigaction <= libc::SIG_IGN
                {
                    continue;
                }
                CTRLC.store(action.sa_sigaction, Ordering::SeqCst);
                action.sa_sigaction = note as extern "C" fn(libc::c_int) as usize;
                libc::sigaction(signal, &action, std::ptr::null_mut());
            }
        }
    }

    pub fn exit_code() -> i32 {
        128 + LAST.load(Ordering::SeqCst)
    }
}

/// Elsewhere, ctrlc's handler is for Ctrl-C and closing the console.
#[cfg(not(unix))]
mod signals {
    pub fn note_which() {}

    pub fn exit_code() -> i32 {
        130
    }
}

fn main() -> ExitCode {
    // Mesa's device-select Vulkan layer connects to a Wayland display while
    // listing adapters, and on a headless machine prints "error:
    // XDG_RUNTIME_DIR is invalid or not set" twice. It only reorders the
    // adapters, which lambert ranks itself, so it is switched off unless
    // the user is steering it (MESA_VK_DEVICE_SELECT) or has set its switch.
    if std::env::var_os("MESA_VK_DEVICE_SELECT").is_none()
        && std::env::var_os("NODEVICE_SELECT").is_none()
    {
        // SAFETY: no other thread exists yet to read the environment.
        unsafe { std::env::set_var("NODEVICE_SELECT", "1") };
    }
    // The CPU kernel the user asks for, decided before any work.
    let asked = std::env::var(lambert::cpu::CPU_KERNEL_ENV).ok();
    lambert::cpu::CpuKernel::select(asked.as_deref());
    // Ctrl-C, SIGTERM or SIGHUP mid-write: no temporary file stays behind
    // (the previous output is untouched: it is only ever replaced whole),
    // and the exit status is 128 + the signal's number, as a shell reports
    // a process the signal killed (130, 143, 129).
    match ctrlc::set_handler(|| lambert::output::remove_temporaries_and_exit(signals::exit_code()))
    {
        Ok(()) => signals::note_which(),
        Err(e) => eprintln!(
            "warning: cannot handle Ctrl-C ({e}): an interrupted write may leave a temporary file"
        ),
    }
    match cli::run() {
        Ok(code) => code,
        // The library gives no advice in flags; the CLI's is --device.
        Err(e @ lambert::error::Error::LoopsCut(_)) => {
            eprintln!("error: {e}: use --device cpu");
            ExitCode::FAILURE
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
