//! Progress bars for long-running commands, on stderr so stdout stays clean for `--json` and
//! pipes; indicatif hides them when stderr is not a terminal (CI logs, redirection).

use indicatif::{ProgressBar, ProgressStyle};

/// A bar counting `len` items, labelled with what is being done.
pub fn progress_bar(len: usize, what: &str) -> ProgressBar {
    let bar = ProgressBar::new(len as u64);
    let style = ProgressStyle::with_template("{msg:>16} [{bar:40}] {pos}/{len} {elapsed}<{eta}")
        .map(|s| s.progress_chars("=> "))
        .unwrap_or_else(|_| ProgressStyle::default_bar());
    bar.set_style(style);
    bar.set_message(what.to_owned());
    bar
}

/// A progress callback `(done, total)` that moves `bar` (and sets its length, which a training
/// run knows only once it starts).
pub fn counter(bar: &ProgressBar) -> impl Fn(usize, usize) + Sync + '_ {
    |done, total| {
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    }
}
