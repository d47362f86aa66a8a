//! The plugin's own GPU tests, in one test binary: each binary links all of Bevy, and CI's
//! disk and link time pay for every one.
//!
//! - [`headless_render`]: a windowless app renders on the software Vulkan driver.
//! - [`ktx2_bevy_loader`]: the pack's KTX2 chunks open in Bevy's own loader.
//! - [`tour_compare`]: GPU against CPU on the architectural tour's pack (ignored by default).

mod common;

mod headless_render;
mod ktx2_bevy_loader;
mod tour_compare;
