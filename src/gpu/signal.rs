//! A wgpu callback's value as a future: how the host waits for the device
//! on every platform. Natively `device.poll` runs the callbacks before the
//! future is first polled; on the web (where `poll` does nothing) they run
//! when the browser's event loop turns, which awaiting lets it do.

use std::future::Future;
use std::pin::Pin;
use std::sync::{Arc, Mutex};
use std::task::{Context, Poll, Waker};

#[derive(Default)]
struct Slot<T> {
    value: Option<T>,
    waker: Option<Waker>,
}

/// The receiving half: a future of the value the callback sends.
pub(super) struct Signal<T>(Arc<Mutex<Slot<T>>>);

/// The sending half, moved into the callback.
pub(super) struct Sender<T>(Arc<Mutex<Slot<T>>>);

/// A signal and the sender a callback fills it through.
pub(super) fn signal<T>() -> (Sender<T>, Signal<T>) {
    let slot = Arc::new(Mutex::new(Slot {
        value: None,
        waker: None,
    }));
    (Sender(slot.clone()), Signal(slot))
}

impl<T> Sender<T> {
    pub fn send(self, value: T) {
        let mut slot = self.0.lock().unwrap_or_else(|e| e.into_inner());
        slot.value = Some(value);
        if let Some(waker) = slot.waker.take() {
            waker.wake();
        }
    }
}

impl<T> Future for Signal<T> {
    type Output = T;

    fn poll(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<T> {
        let mut slot = self.0.lock().unwrap_or_else(|e| e.into_inner());
        match slot.value.take() {
            Some(value) => Poll::Ready(value),
            None => {
                slot.waker = Some(cx.waker().clone());
                Poll::Pending
            }
        }
    }
}
