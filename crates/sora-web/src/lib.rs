//! The browser explorer's engine: the sora library behind a C ABI that a
//! Web Worker calls (`web/worker.js`), with no JavaScript glue generator.
//!
//! Protocol: the worker copies a UTF-8 JSON request into memory it got from
//! [`sora_alloc`], calls [`sora_call`], and reads the reply: a JSON text
//! ([`sora_reply_json_ptr`], [`sora_reply_json_len`]) and, for images and
//! files, bytes ([`sora_reply_bytes_ptr`], [`sora_reply_bytes_len`]). The
//! requests and replies are in [`request`]; a failure is a reply
//! `{"error": "<the library's one-line message>"}` and status 1, never a
//! trap. The reply stays valid until the next call.
//!
//! State: the engine keeps the last atmosphere and the last sky of each
//! image quality (see [`engine::Engine`]), so that clicking a direction or
//! downloading the image does not recompute what is on the screen. This is
//! the only global state of the project, and it is in this binary-like
//! layer, not in the library.

pub mod atmosphere_controls;
pub mod engine;
pub mod request;

use std::cell::RefCell;

use engine::{Engine, Reply};

thread_local! {
    /// The engine and the last reply (a Web Worker has one thread).
    static STATE: RefCell<(Engine, Reply)> = RefCell::new((Engine::default(), Reply::default()));
}

#[cfg(target_arch = "wasm32")]
#[link(wasm_import_module = "env")]
unsafe extern "C" {
    /// The worker's progress callback (`web/worker.js`): posts the
    /// fraction of the running request's work done to the page.
    #[link_name = "sora_progress"]
    fn sora_progress_import(fraction: f64);
}

/// Reports that `fraction` (0..1) of a long request's work is done: to the
/// worker's `env.sora_progress` import in WebAssembly, nowhere natively.
pub fn report_progress(fraction: f64) {
    #[cfg(target_arch = "wasm32")]
    // SAFETY: an imported JavaScript function taking one number.
    unsafe {
        sora_progress_import(fraction)
    };
    #[cfg(not(target_arch = "wasm32"))]
    let _ = fraction;
}

/// Memory for a request of `len` bytes (freed with [`sora_free`]).
#[unsafe(no_mangle)]
pub extern "C" fn sora_alloc(len: usize) -> *mut u8 {
    let mut buffer = Vec::<u8>::with_capacity(len.max(1));
    let pointer = buffer.as_mut_ptr();
    std::mem::forget(buffer);
    pointer
}

/// Frees memory from [`sora_alloc`] of the same `len`.
///
/// # Safety
/// `pointer` must come from `sora_alloc(len)` and not be freed twice.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn sora_free(pointer: *mut u8, len: usize) {
    // SAFETY: the caller passes back what sora_alloc(len) returned.
    drop(unsafe { Vec::from_raw_parts(pointer, 0, len.max(1)) });
}

/// Runs the JSON request of `len` bytes at `pointer`: 0 when it succeeded,
/// 1 when the reply is an error.
///
/// # Safety
/// `pointer` must point to `len` readable bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn sora_call(pointer: *const u8, len: usize) -> u32 {
    // SAFETY: the caller passes `len` readable bytes.
    let request = unsafe { std::slice::from_raw_parts(pointer, len) };
    STATE.with(|state| {
        let (engine, reply) = &mut *state.borrow_mut();
        *reply = engine.call_bytes(request);
        u32::from(reply.is_error)
    })
}

/// The last reply's JSON text.
#[unsafe(no_mangle)]
pub extern "C" fn sora_reply_json_ptr() -> *const u8 {
    STATE.with(|state| state.borrow().1.json.as_ptr())
}

/// The length of the last reply's JSON text, bytes.
#[unsafe(no_mangle)]
pub extern "C" fn sora_reply_json_len() -> usize {
    STATE.with(|state| state.borrow().1.json.len())
}

/// The last reply's bytes (RGBA pixels, an OpenEXR file; empty otherwise).
#[unsafe(no_mangle)]
pub extern "C" fn sora_reply_bytes_ptr() -> *const u8 {
    STATE.with(|state| state.borrow().1.bytes.as_ptr())
}

/// The length of the last reply's bytes.
#[unsafe(no_mangle)]
pub extern "C" fn sora_reply_bytes_len() -> usize {
    STATE.with(|state| state.borrow().1.bytes.len())
}
