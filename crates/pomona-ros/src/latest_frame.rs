//! A one-slot mailbox between the thread that receives frames and the thread that detects:
//! putting a frame replaces one not yet taken (it is stale: the camera has moved on), so when
//! detection is slower than the camera the node always works on the newest frame and memory
//! stays at one frame.

use std::sync::{Condvar, Mutex, MutexGuard, PoisonError};

#[derive(Debug)]
struct Slot<T> {
    value: Option<T>,
    closed: bool,
    replaced: u64,
}

/// The mailbox.
#[derive(Debug)]
pub struct LatestFrame<T> {
    slot: Mutex<Slot<T>>,
    ready: Condvar,
}

impl<T> Default for LatestFrame<T> {
    fn default() -> Self {
        Self {
            slot: Mutex::new(Slot {
                value: None,
                closed: false,
                replaced: 0,
            }),
            ready: Condvar::new(),
        }
    }
}

impl<T> LatestFrame<T> {
    fn lock(&self) -> MutexGuard<'_, Slot<T>> {
        // A panic elsewhere cannot leave the slot half-written: recover the guard.
        self.slot.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Puts `value`, dropping the one waiting (counted in [`LatestFrame::replaced`]).
    pub fn put(&self, value: T) {
        let mut slot = self.lock();
        if slot.value.replace(value).is_some() {
            slot.replaced += 1;
        }
        self.ready.notify_one();
    }

    /// Waits for a value and takes it; `None` once the mailbox is closed and empty.
    pub fn take(&self) -> Option<T> {
        let mut slot = self.lock();
        loop {
            if let Some(value) = slot.value.take() {
                return Some(value);
            }
            if slot.closed {
                return None;
            }
            slot = self
                .ready
                .wait(slot)
                .unwrap_or_else(PoisonError::into_inner);
        }
    }

    /// Wakes the taker for good: [`LatestFrame::take`] returns what is waiting, then `None`.
    pub fn close(&self) {
        self.lock().closed = true;
        self.ready.notify_all();
    }

    /// How many values were dropped unread.
    pub fn replaced(&self) -> u64 {
        self.lock().replaced
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;

    #[test]
    fn newest_value_wins_and_close_ends_the_taker() {
        let mailbox = Arc::new(LatestFrame::default());
        mailbox.put(1);
        mailbox.put(2);
        assert_eq!(mailbox.replaced(), 1);
        assert_eq!(mailbox.take(), Some(2));
        let taker = {
            let mailbox = Arc::clone(&mailbox);
            std::thread::spawn(move || {
                let mut seen = Vec::new();
                while let Some(v) = mailbox.take() {
                    seen.push(v);
                }
                seen
            })
        };
        mailbox.put(3);
        std::thread::sleep(std::time::Duration::from_millis(50));
        mailbox.close();
        let seen = taker.join().unwrap_or_default();
        assert_eq!(seen, vec![3]);
        assert_eq!(mailbox.take(), None);
    }
}
