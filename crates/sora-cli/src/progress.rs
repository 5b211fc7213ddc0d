//! Progress on stderr: one place for the bars and spinners every command
//! shows while it works. indicatif draws them only when stderr is a
//! terminal (hidden in pipes, files and tests), so what a command prints
//! on stdout is the same with or without them.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// A bar of `len` steps on stderr drawn with indicatif's `template`
/// (`{bar:40}`, `{pos}/{len}`, `{eta}`, `{elapsed}`, `{msg}`), `=> ` as
/// its fill.
pub fn bar(len: u64, template: &str) -> ProgressBar {
    let bar = ProgressBar::with_draw_target(Some(len), ProgressDrawTarget::stderr());
    if let Ok(style) = ProgressStyle::with_template(template) {
        bar.set_style(style.progress_chars("=> "));
    }
    bar
}

/// A spinner on stderr with `template`, ticking on its own (for work
/// whose length is not known as it runs).
pub fn spinner(template: &str) -> ProgressBar {
    let spinner = ProgressBar::with_draw_target(None, ProgressDrawTarget::stderr());
    if let Ok(style) = ProgressStyle::with_template(template) {
        spinner.set_style(style);
    }
    spinner.enable_steady_tick(std::time::Duration::from_millis(100));
    spinner
}
