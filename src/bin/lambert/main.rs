//! The `lambert` command line: parses, calls the library, prints.

use std::process::ExitCode;

mod cli;
mod plot;
mod progress_bar;
mod view;

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
    // (the previous output is untouched: it is only ever replaced whole).
    if let Err(e) = ctrlc::set_handler(|| lambert::output::remove_temporaries_and_exit(130)) {
        eprintln!(
            "warning: cannot handle Ctrl-C ({e}): an interrupted write may leave a temporary file"
        );
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
