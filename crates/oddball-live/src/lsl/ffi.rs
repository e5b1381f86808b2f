//! liblsl's C API, loaded at run time: the only unsafe code of this crate.
//!
//! # Why it is written here
//! LSL is liblsl, a C++ library with a stable C API (`lsl_c.h`, the same declarations from 1.13
//! to 1.18). The `lsl` crate builds liblsl 1.13 from source with cmake and g++, which a Rust user
//! does not have, so LSL sat behind a cargo feature the prebuilt program lacked. No well-kept
//! crate loads liblsl at run time; pylsl does, with `ctypes`, and this module does what it does
//! with `libloading`: it opens a liblsl file ([`super::find`] says where it looks) once per
//! process ([`liblsl`]) and declares only the functions [`super`] calls, each with its signature
//! from `lsl_c.h`. Above this module the code is safe Rust: owned handles
//! ([`StreamInfo`], [`Inlet`], [`Outlet`]) destroyed on drop, borrowed XML nodes ([`Xml`]),
//! slices in, `String`s and [`Fault`]s out.
//!
//! # What the unsafe blocks rely on
//! * Opening a file runs its initialisers: a file is only opened as liblsl when the user named
//!   it, the dynamic loader finds it under liblsl's names, or it is pylsl's bundled copy; the
//!   trust pylsl puts in the same files.
//! * Each symbol has the type `lsl_c.h` declares for it (the `api!` list below; `int32_t` is
//!   `i32`, `unsigned long` `c_ulong`, the enum `lsl_channel_format_t` a C `int`, every handle a
//!   pointer). A library missing one of them is refused. The function pointers are copied out of
//!   the [`Library`] into the same [`Liblsl`] that keeps it, and are called only through it; the
//!   process's [`Liblsl`] lives in a `static` and is never unloaded.
//! * Handles: each owned wrapper holds the non-null handle its `lsl_create_*` (or
//!   `lsl_resolve_byprop`, `lsl_get_fullinfo`) returned and destroys it once, in `Drop`. A
//!   string liblsl returns from a stream info or an XML node lives as long as that info and is
//!   copied into a `String` at once; an [`Xml`] node borrows its [`StreamInfo`].
//! * Buffers: every buffer handed over is a Rust slice and its length is the element count
//!   passed with it; liblsl writes no more than that. Strings of `lsl_pull_sample_str` are
//!   `malloc`ed by liblsl, one per channel (also when no sample came), and each is freed once
//!   with `lsl_destroy_string`.
//! * Threads: liblsl's inlets, outlets and stream infos are C++ objects reached through opaque
//!   handles with no thread affinity, so the wrappers are [`Send`]; they are not `Sync`: one
//!   thread at a time uses each.
#![allow(unsafe_code)]

use std::ffi::{c_char, c_int, c_ulong, c_void, CStr, CString};
use std::fmt;
use std::marker::PhantomData;
use std::path::Path;
use std::ptr::{self, NonNull};
use std::sync::OnceLock;

use libloading::Library;

use super::find::{candidates, liblsl_of_python, Candidate, PYTHON};
use crate::LiveError;

/// A liblsl handle (`lsl_streaminfo`, `lsl_inlet`, `lsl_outlet`, `lsl_xml_ptr`).
type Handle = *mut c_void;

/// Declares the liblsl functions used (name without `lsl_`, C signature from `lsl_c.h`).
macro_rules! api {
    ($($name:ident: fn($($arg:ty),*) $(-> $ret:ty)?;)*) => {
        /// The liblsl functions this crate calls.
        struct Fns {
            $($name: unsafe extern "C" fn($($arg),*) $(-> $ret)?,)*
        }

        impl Fns {
            /// Looks every function up in `lib`, naming the first one missing.
            ///
            /// # Safety
            /// `lib` must be liblsl, whose exported symbols have the signatures above.
            unsafe fn load(lib: &Library) -> Result<Self, String> {
                Ok(Self {
                    $($name: {
                        let name = concat!("lsl_", stringify!($name), "\0");
                        // SAFETY: the caller's promise: the symbol has this type.
                        let symbol = unsafe {
                            lib.get::<unsafe extern "C" fn($($arg),*) $(-> $ret)?>(name.as_bytes())
                        };
                        *symbol.map_err(|e| format!("it has no {}: {e}", name.trim_end_matches('\0')))?
                    },)*
                })
            }
        }
    };
}

api! {
    library_version: fn() -> i32;
    library_info: fn() -> *const c_char;
    local_clock: fn() -> f64;
    resolve_byprop: fn(*mut Handle, u32, *const c_char, *const c_char, i32, f64) -> i32;
    create_streaminfo: fn(*const c_char, *const c_char, i32, f64, c_int, *const c_char) -> Handle;
    destroy_streaminfo: fn(Handle);
    get_name: fn(Handle) -> *const c_char;
    get_hostname: fn(Handle) -> *const c_char;
    get_channel_count: fn(Handle) -> i32;
    get_nominal_srate: fn(Handle) -> f64;
    get_channel_format: fn(Handle) -> c_int;
    get_desc: fn(Handle) -> Handle;
    child: fn(Handle, *const c_char) -> Handle;
    next_sibling_n: fn(Handle, *const c_char) -> Handle;
    empty: fn(Handle) -> i32;
    child_value_n: fn(Handle, *const c_char) -> *const c_char;
    append_child: fn(Handle, *const c_char) -> Handle;
    append_child_value: fn(Handle, *const c_char, *const c_char) -> Handle;
    create_outlet: fn(Handle, i32, i32) -> Handle;
    destroy_outlet: fn(Handle);
    push_sample_strtp: fn(Handle, *const *const c_char, f64, i32) -> i32;
    push_chunk_ftnp: fn(Handle, *const f32, c_ulong, *const f64, i32) -> i32;
    have_consumers: fn(Handle) -> i32;
    wait_for_consumers: fn(Handle, f64) -> i32;
    create_inlet: fn(Handle, i32, i32, i32) -> Handle;
    destroy_inlet: fn(Handle);
    get_fullinfo: fn(Handle, f64, *mut i32) -> Handle;
    open_stream: fn(Handle, f64, *mut i32);
    time_correction: fn(Handle, f64, *mut i32) -> f64;
    pull_sample_f: fn(Handle, *mut f32, i32, f64, *mut i32) -> f64;
    pull_sample_d: fn(Handle, *mut f64, i32, f64, *mut i32) -> f64;
    pull_sample_i: fn(Handle, *mut i32, i32, f64, *mut i32) -> f64;
    pull_sample_str: fn(Handle, *mut *mut c_char, i32, f64, *mut i32) -> f64;
    pull_chunk_d: fn(Handle, *mut f64, *mut f64, c_ulong, c_ulong, f64, *mut i32) -> c_ulong;
    destroy_string: fn(*mut c_char);
}

/// `lsl_last_error` (liblsl ≥ 1.14): the message of the last exception on this thread.
type LastError = unsafe extern "C" fn() -> *const c_char;

/// liblsl's error codes (`lsl_error_code_t`).
const TIMEOUT_ERROR: i32 = -1;
const LOST_ERROR: i32 = -2;

/// A liblsl channel format (`lsl_channel_format_t`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    Float32,
    Double64,
    String,
    Int32,
    Int16,
    Int8,
    Int64,
    /// `cft_undefined` or a value this code does not know.
    Undefined,
}

impl Format {
    fn from_c(v: c_int) -> Self {
        match v {
            1 => Self::Float32,
            2 => Self::Double64,
            3 => Self::String,
            4 => Self::Int32,
            5 => Self::Int16,
            6 => Self::Int8,
            7 => Self::Int64,
            _ => Self::Undefined,
        }
    }

    fn to_c(self) -> c_int {
        match self {
            Self::Float32 => 1,
            Self::Double64 => 2,
            Self::String => 3,
            Self::Int32 => 4,
            Self::Int16 => 5,
            Self::Int8 => 6,
            Self::Int64 => 7,
            Self::Undefined => 0,
        }
    }
}

impl fmt::Display for Format {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Float32 => "float32",
            Self::Double64 => "double64",
            Self::String => "string",
            Self::Int32 => "int32",
            Self::Int16 => "int16",
            Self::Int8 => "int8",
            Self::Int64 => "int64",
            Self::Undefined => "undefined",
        })
    }
}

/// A failed liblsl call: its error code (0 when it only returned nothing) and what liblsl said.
#[derive(Debug, Clone, PartialEq)]
pub struct Fault {
    pub code: i32,
    pub message: String,
}

impl Fault {
    /// liblsl's `lsl_lost_error`: the stream's source is gone for good.
    pub fn is_lost(&self) -> bool {
        self.code == LOST_ERROR
    }
}

impl fmt::Display for Fault {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

/// A loaded liblsl.
pub struct Liblsl {
    fns: Fns,
    last_error: Option<LastError>,
    place: String,
    version: i32,
    info: String,
    /// Keeps the library loaded while `fns` may be called (dropped last).
    _lib: Library,
}

impl fmt::Debug for Liblsl {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Liblsl")
            .field("place", &self.place)
            .field("version", &self.version)
            .field("info", &self.info)
            .finish()
    }
}

impl Liblsl {
    /// Where it was loaded from: a path, or a file name the dynamic loader found.
    pub fn place(&self) -> &str {
        &self.place
    }

    /// `lsl_library_version()`: major · 100 + minor (118 for 1.18).
    pub fn version(&self) -> i32 {
        self.version
    }

    /// `lsl_library_info()`: the build it is (git tag, compiler, …).
    pub fn info(&self) -> &str {
        &self.info
    }

    /// The version as people write it: the release tag in the build info when it agrees with
    /// [`Liblsl::version`] (`1.18.0.b6`), else major.minor (`1.18`).
    pub fn version_text(&self) -> String {
        let short = format!("{}.{}", self.version / 100, self.version % 100);
        // `…/branch:refs/tags/v1.18.0.b6/build:…`
        let tag = self
            .info
            .split_once("refs/tags/v")
            .and_then(|(_, rest)| rest.split('/').next());
        match tag {
            Some(t) if t == short || t.starts_with(&format!("{short}.")) => t.to_string(),
            _ => short,
        }
    }

    /// liblsl's clock, s.
    pub fn local_clock(&self) -> f64 {
        // SAFETY: no arguments; reads a clock.
        unsafe { (self.fns.local_clock)() }
    }

    /// A [`Fault`] for error code `code` (0: a call returned nothing), with liblsl's own
    /// message when it has one.
    fn fault(&self, code: i32) -> Fault {
        let said = match (code, self.last_error) {
            (TIMEOUT_ERROR, _) => "timed out".to_string(),
            (LOST_ERROR, _) => "the stream is lost".to_string(),
            // SAFETY: no arguments; returns a thread-local C string (or null), copied at once.
            (_, Some(last)) => unsafe { text(last()) },
            (_, None) => String::new(),
        };
        let message = match (said.is_empty(), code) {
            (true, 0) => "liblsl gave no reason".to_string(),
            (true, _) => format!("liblsl error {code}"),
            (false, _) => said,
        };
        Fault { code, message }
    }

    /// `Ok` for error code 0, else the fault.
    fn check(&self, ec: i32) -> Result<(), Fault> {
        if ec == 0 {
            Ok(())
        } else {
            Err(self.fault(ec))
        }
    }
}

/// A C string's text (lossy); "" for null.
///
/// # Safety
/// `p` is null or a NUL-terminated string valid for the call.
unsafe fn text(p: *const c_char) -> String {
    if p.is_null() {
        String::new()
    } else {
        // SAFETY: the caller's promise.
        unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned()
    }
}

/// `s` as a C string (a NUL byte cannot be passed to liblsl).
fn c_string(s: &str) -> Result<CString, Fault> {
    CString::new(s).map_err(|_| Fault {
        code: 0,
        message: format!("{s:?} contains a NUL byte"),
    })
}

// ---- loading the library ----

/// Opens `file` as liblsl: a library that exports every function this crate calls.
fn open(c: &Candidate) -> Result<Liblsl, String> {
    // SAFETY: opening runs the file's initialisers; the file is liblsl by its name or by the
    // user's word (see the module documentation).
    let lib = unsafe { Library::new(&c.file) }.map_err(|e| {
        // libloading says "dlopen failed"; the loader's own words are its source.
        let mut why = e.to_string();
        let mut cause = std::error::Error::source(&e);
        while let Some(c) = cause {
            why = format!("{why}: {c}");
            cause = c.source();
        }
        why
    })?;
    // SAFETY: a library that exports liblsl's names is liblsl, whose symbols have the
    // signatures of `lsl_c.h`.
    let fns = unsafe { Fns::load(&lib) }?;
    // SAFETY: as above; `lsl_last_error` is `const char *(void)` where it exists (≥ 1.14).
    let last_error = unsafe { lib.get::<LastError>(b"lsl_last_error\0") }
        .ok()
        .map(|s| *s);
    // SAFETY: no arguments; the info is a static C string, copied at once.
    let (version, info) = unsafe { ((fns.library_version)(), text((fns.library_info)())) };
    Ok(Liblsl {
        fns,
        last_error,
        place: c.file.display().to_string(),
        version,
        info,
        _lib: lib,
    })
}

/// Opens the first of `candidates` that is liblsl. The error lists every file tried and why it
/// failed, and says how to get liblsl.
pub fn load_from(candidates: &[Candidate]) -> Result<Liblsl, LiveError> {
    let mut tried = Vec::new();
    for c in candidates {
        match open(c) {
            Ok(lib) => return Ok(lib),
            Err(why) => tried.push(format!("{} ({}): {why}", c.file.display(), c.origin)),
        }
    }
    Err(LiveError::LiblslNotFound { tried })
}

/// The process's liblsl, loaded at the first call from the first of [`candidates`] (this
/// process's environment) that loads, else from the pylsl of `python3`; the same library, or
/// the same error, from then on.
pub fn liblsl() -> Result<&'static Liblsl, LiveError> {
    static LIBLSL: OnceLock<Result<Liblsl, Vec<String>>> = OnceLock::new();
    let loaded = LIBLSL.get_or_init(|| {
        let found = candidates(|name| std::env::var_os(name));
        let explicit = found.first().is_some_and(|c| c.origin == "ODDBALL_LIBLSL");
        let mut tried = match load_from(&found) {
            Ok(lib) => return Ok(lib),
            Err(LiveError::LiblslNotFound { tried }) => tried,
            Err(e) => vec![e.to_string()],
        };
        if !explicit {
            match liblsl_of_python(Path::new(PYTHON)) {
                Some(file) => {
                    let c = Candidate::new(file, format!("pylsl of {PYTHON}"));
                    match load_from(std::slice::from_ref(&c)) {
                        Ok(lib) => return Ok(lib),
                        Err(LiveError::LiblslNotFound { tried: t }) => tried.extend(t),
                        Err(e) => tried.push(e.to_string()),
                    }
                }
                None => tried.push(format!("{PYTHON}: no pylsl with a bundled liblsl")),
            }
        }
        Err(tried)
    });
    loaded.as_ref().map_err(|tried| LiveError::LiblslNotFound {
        tried: tried.clone(),
    })
}

// ---- stream infos and their XML ----

/// An owned `lsl_streaminfo`.
#[derive(Debug)]
pub struct StreamInfo {
    handle: NonNull<c_void>,
    lib: &'static Liblsl,
}

// SAFETY: see the module documentation (no thread affinity; not `Sync`).
unsafe impl Send for StreamInfo {}

impl Drop for StreamInfo {
    fn drop(&mut self) {
        // SAFETY: the handle is owned and destroyed only here.
        unsafe { (self.lib.fns.destroy_streaminfo)(self.handle.as_ptr()) }
    }
}

impl StreamInfo {
    /// `lsl_create_streaminfo`.
    pub fn new(
        lib: &'static Liblsl,
        name: &str,
        stream_type: &str,
        channel_count: i32,
        nominal_srate: f64,
        format: Format,
        source_id: &str,
    ) -> Result<Self, Fault> {
        let (n, t, s) = (
            c_string(name)?,
            c_string(stream_type)?,
            c_string(source_id)?,
        );
        // SAFETY: C strings that live through the call; liblsl copies them.
        let h = unsafe {
            (lib.fns.create_streaminfo)(
                n.as_ptr(),
                t.as_ptr(),
                channel_count,
                nominal_srate,
                format.to_c(),
                s.as_ptr(),
            )
        };
        NonNull::new(h)
            .map(|handle| Self { handle, lib })
            .ok_or_else(|| lib.fault(0))
    }

    /// Reads one of the info's strings.
    fn string(&self, f: unsafe extern "C" fn(Handle) -> *const c_char) -> String {
        // SAFETY: a live handle; the string lives as long as the info and is copied at once.
        unsafe { text(f(self.handle.as_ptr())) }
    }

    pub fn name(&self) -> String {
        self.string(self.lib.fns.get_name)
    }

    /// The host the stream comes from.
    pub fn hostname(&self) -> String {
        self.string(self.lib.fns.get_hostname)
    }

    pub fn channel_count(&self) -> i32 {
        // SAFETY: a live handle.
        unsafe { (self.lib.fns.get_channel_count)(self.handle.as_ptr()) }
    }

    /// Hz; 0 for an irregular rate.
    pub fn nominal_srate(&self) -> f64 {
        // SAFETY: a live handle.
        unsafe { (self.lib.fns.get_nominal_srate)(self.handle.as_ptr()) }
    }

    pub fn channel_format(&self) -> Format {
        // SAFETY: a live handle.
        Format::from_c(unsafe { (self.lib.fns.get_channel_format)(self.handle.as_ptr()) })
    }

    /// The `desc` element, for reading or extending.
    pub fn desc(&self) -> Xml<'_> {
        // SAFETY: a live handle; the node lives in the info, which the result borrows.
        let node = unsafe { (self.lib.fns.get_desc)(self.handle.as_ptr()) };
        Xml {
            node,
            lib: self.lib,
            _info: PhantomData,
        }
    }
}

/// A node of a stream info's XML (`lsl_xml_ptr`), possibly empty (liblsl's empty node answers
/// every query with another empty node or "").
#[derive(Debug, Clone, Copy)]
pub struct Xml<'a> {
    node: Handle,
    lib: &'static Liblsl,
    _info: PhantomData<&'a StreamInfo>,
}

impl<'a> Xml<'a> {
    fn with(self, node: Handle) -> Self {
        Self { node, ..self }
    }

    /// Calls `f(node, name)`.
    fn named(self, f: unsafe extern "C" fn(Handle, *const c_char) -> Handle, name: &str) -> Self {
        let Ok(name) = c_string(name) else {
            return self.with(ptr::null_mut());
        };
        // SAFETY: a node of a live info (borrowed) and a C string living through the call.
        self.with(unsafe { f(self.node, name.as_ptr()) })
    }

    /// The first child element called `name`.
    pub fn child(self, name: &str) -> Self {
        self.named(self.lib.fns.child, name)
    }

    /// The next sibling element called `name`.
    pub fn next_sibling(self, name: &str) -> Self {
        self.named(self.lib.fns.next_sibling_n, name)
    }

    /// Whether this is the empty node (no such element).
    pub fn is_empty(self) -> bool {
        // SAFETY: a node of a live info; liblsl accepts the empty (null) node.
        self.node.is_null() || unsafe { (self.lib.fns.empty)(self.node) } != 0
    }

    /// The text of the child element `name` ("" when there is none).
    pub fn child_value(self, name: &str) -> String {
        let Ok(name) = c_string(name) else {
            return String::new();
        };
        if self.node.is_null() {
            return String::new();
        }
        // SAFETY: as for `named`; the text lives in the info and is copied at once.
        unsafe { text((self.lib.fns.child_value_n)(self.node, name.as_ptr())) }
    }

    /// Appends the element `name`; returns it.
    pub fn append_child(self, name: &str) -> Self {
        self.named(self.lib.fns.append_child, name)
    }

    /// Appends `<name>value</name>`; returns this node.
    pub fn append_child_value(self, name: &str, value: &str) -> Self {
        if let (Ok(n), Ok(v)) = (c_string(name), c_string(value)) {
            if !self.node.is_null() {
                // SAFETY: as for `named`; liblsl copies both strings.
                unsafe { (self.lib.fns.append_child_value)(self.node, n.as_ptr(), v.as_ptr()) };
            }
        }
        self
    }
}

/// `lsl_resolve_byprop`: up to `max` streams whose `prop` is `value`, waiting up to `timeout`
/// s for at least `minimum`.
pub fn resolve_byprop(
    lib: &'static Liblsl,
    prop: &str,
    value: &str,
    max: usize,
    minimum: i32,
    timeout: f64,
) -> Result<Vec<StreamInfo>, Fault> {
    let (p, v) = (c_string(prop)?, c_string(value)?);
    let mut found: Vec<Handle> = vec![ptr::null_mut(); max.max(1)];
    let slots = u32::try_from(found.len()).unwrap_or(u32::MAX);
    // SAFETY: `found` has `slots` elements, liblsl writes at most that many handles, each
    // owned by us from then on; the C strings live through the call.
    let n = unsafe {
        (lib.fns.resolve_byprop)(
            found.as_mut_ptr(),
            slots,
            p.as_ptr(),
            v.as_ptr(),
            minimum,
            timeout,
        )
    };
    if n < 0 {
        return Err(lib.fault(n));
    }
    Ok(found
        .into_iter()
        .take(n as usize)
        .filter_map(NonNull::new)
        .map(|handle| StreamInfo { handle, lib })
        .collect())
}

// ---- inlets ----

/// An owned `lsl_inlet`.
#[derive(Debug)]
pub struct Inlet {
    handle: NonNull<c_void>,
    lib: &'static Liblsl,
}

// SAFETY: see the module documentation (no thread affinity; not `Sync`).
unsafe impl Send for Inlet {}

impl Drop for Inlet {
    fn drop(&mut self) {
        // SAFETY: the handle is owned and destroyed only here.
        unsafe { (self.lib.fns.destroy_inlet)(self.handle.as_ptr()) }
    }
}

impl Inlet {
    /// `lsl_create_inlet` on a resolved stream (liblsl copies the info). With `recover`, a
    /// stream with a source id that goes away is waited for; without, its loss is an error.
    pub fn new(
        info: &StreamInfo,
        max_buflen: i32,
        max_chunklen: i32,
        recover: bool,
    ) -> Result<Self, Fault> {
        let lib = info.lib;
        // SAFETY: a live info handle.
        let h = unsafe {
            (lib.fns.create_inlet)(
                info.handle.as_ptr(),
                max_buflen,
                max_chunklen,
                i32::from(recover),
            )
        };
        NonNull::new(h)
            .map(|handle| Self { handle, lib })
            .ok_or_else(|| lib.fault(0))
    }

    /// `lsl_get_fullinfo`: the stream's info with its `desc`.
    pub fn full_info(&self, timeout: f64) -> Result<StreamInfo, Fault> {
        let mut ec = 0;
        // SAFETY: a live handle and an error code slot; the result is ours to destroy.
        let h = unsafe { (self.lib.fns.get_fullinfo)(self.handle.as_ptr(), timeout, &mut ec) };
        self.lib.check(ec)?;
        NonNull::new(h)
            .map(|handle| StreamInfo {
                handle,
                lib: self.lib,
            })
            .ok_or_else(|| self.lib.fault(0))
    }

    /// `lsl_open_stream`: connects now rather than at the first pull.
    pub fn open_stream(&self, timeout: f64) -> Result<(), Fault> {
        let mut ec = 0;
        // SAFETY: a live handle and an error code slot.
        unsafe { (self.lib.fns.open_stream)(self.handle.as_ptr(), timeout, &mut ec) };
        self.lib.check(ec)
    }

    /// `lsl_time_correction`: the offset to add to the stream's timestamps, s.
    pub fn time_correction(&self, timeout: f64) -> Result<f64, Fault> {
        let mut ec = 0;
        // SAFETY: a live handle and an error code slot.
        let c = unsafe { (self.lib.fns.time_correction)(self.handle.as_ptr(), timeout, &mut ec) };
        self.lib.check(ec)?;
        Ok(c)
    }

    /// The error code of a pull; a timeout is not an error (nothing came).
    fn pulled(&self, ts: f64, ec: i32) -> Result<f64, Fault> {
        match ec {
            0 | TIMEOUT_ERROR => Ok(ts),
            ec => Err(self.lib.fault(ec)),
        }
    }

    /// A pull of one sample into `buf` (one value per channel) by `f`, one of
    /// `lsl_pull_sample_{d,f,i}`.
    fn pull_into<T>(
        &self,
        f: unsafe extern "C" fn(Handle, *mut T, i32, f64, *mut i32) -> f64,
        buf: &mut [T],
        timeout: f64,
    ) -> Result<f64, Fault> {
        let mut ec = 0;
        let n = i32::try_from(buf.len()).unwrap_or(i32::MAX);
        // SAFETY: `buf` holds `n` elements of the type `f` writes, liblsl writes at most that
        // many (and none unless `n` is the channel count).
        let ts = unsafe { f(self.handle.as_ptr(), buf.as_mut_ptr(), n, timeout, &mut ec) };
        self.pulled(ts, ec)
    }

    /// `lsl_pull_sample_d` into `buf` (one value per channel): the sample's timestamp on the
    /// sender's clock, or 0 when none came within `timeout` s.
    pub fn pull_sample_f64(&self, buf: &mut [f64], timeout: f64) -> Result<f64, Fault> {
        self.pull_into(self.lib.fns.pull_sample_d, buf, timeout)
    }

    /// As [`Inlet::pull_sample_f64`], as float32 (`lsl_pull_sample_f`).
    pub fn pull_sample_f32(&self, buf: &mut [f32], timeout: f64) -> Result<f64, Fault> {
        self.pull_into(self.lib.fns.pull_sample_f, buf, timeout)
    }

    /// As [`Inlet::pull_sample_f64`], as int32 (`lsl_pull_sample_i`).
    pub fn pull_sample_i32(&self, buf: &mut [i32], timeout: f64) -> Result<f64, Fault> {
        self.pull_into(self.lib.fns.pull_sample_i, buf, timeout)
    }

    /// As [`Inlet::pull_sample_f64`], as strings (`lsl_pull_sample_str`): `out` gets one string
    /// per channel when a sample came.
    pub fn pull_sample_strings(
        &self,
        n_channels: usize,
        out: &mut Vec<String>,
        timeout: f64,
    ) -> Result<f64, Fault> {
        let mut ptrs: Vec<*mut c_char> = vec![ptr::null_mut(); n_channels];
        let n = i32::try_from(n_channels).unwrap_or(i32::MAX);
        let mut ec = 0;
        // SAFETY: `ptrs` holds `n` null pointers; liblsl sets at most that many to strings it
        // allocated (also when no sample came).
        let ts = unsafe {
            (self.lib.fns.pull_sample_str)(
                self.handle.as_ptr(),
                ptrs.as_mut_ptr(),
                n,
                timeout,
                &mut ec,
            )
        };
        out.clear();
        for p in ptrs {
            if !p.is_null() {
                // SAFETY: a string liblsl allocated for us: read, then freed once.
                unsafe {
                    out.push(text(p));
                    (self.lib.fns.destroy_string)(p);
                }
            }
        }
        self.pulled(ts, ec)
    }

    /// `lsl_pull_chunk_d`: the samples that have arrived, up to `ts.len()` of them, into `data`
    /// (sample after sample, `data.len() / ts.len()` values each) and `ts`, without waiting.
    /// Returns the count of samples.
    pub fn pull_chunk_f64(&self, data: &mut [f64], ts: &mut [f64]) -> Result<usize, Fault> {
        if ts.is_empty() {
            return Ok(0);
        }
        let per = data.len() / ts.len();
        let mut ec = 0;
        // SAFETY: `data` holds at least `per · ts.len()` and `ts` `ts.len()` elements; liblsl
        // writes at most those counts.
        let values = unsafe {
            (self.lib.fns.pull_chunk_d)(
                self.handle.as_ptr(),
                data.as_mut_ptr(),
                ts.as_mut_ptr(),
                (per * ts.len()) as c_ulong,
                ts.len() as c_ulong,
                0.0,
                &mut ec,
            )
        };
        self.pulled(0.0, ec)?;
        Ok((values as usize).checked_div(per).unwrap_or(0))
    }
}

// ---- outlets ----

/// An owned `lsl_outlet`.
#[derive(Debug)]
pub struct Outlet {
    handle: NonNull<c_void>,
    lib: &'static Liblsl,
    /// The stream's channel count: liblsl reads that many values per sample.
    channels: usize,
}

// SAFETY: see the module documentation (no thread affinity; not `Sync`).
unsafe impl Send for Outlet {}

impl Drop for Outlet {
    fn drop(&mut self) {
        // SAFETY: the handle is owned and destroyed only here.
        unsafe { (self.lib.fns.destroy_outlet)(self.handle.as_ptr()) }
    }
}

impl Outlet {
    /// `lsl_create_outlet` (liblsl copies the info).
    pub fn new(info: &StreamInfo, chunk_size: i32, max_buffered: i32) -> Result<Self, Fault> {
        let lib = info.lib;
        let channels = usize::try_from(info.channel_count()).unwrap_or(0);
        // SAFETY: a live info handle.
        let h = unsafe { (lib.fns.create_outlet)(info.handle.as_ptr(), chunk_size, max_buffered) };
        NonNull::new(h)
            .map(|handle| Self {
                handle,
                lib,
                channels,
            })
            .ok_or_else(|| lib.fault(0))
    }

    /// A fault for a sample of the wrong size (liblsl would read past it).
    fn wrong_size(&self, what: String) -> Fault {
        Fault {
            code: 0,
            message: format!("sending {what} on a {}-channel stream", self.channels),
        }
    }

    /// `lsl_push_sample_strtp`: one string per channel (NUL bytes dropped), stamped
    /// `timestamp` (0 = now).
    pub fn push_strings(
        &self,
        sample: &[&str],
        timestamp: f64,
        pushthrough: bool,
    ) -> Result<(), Fault> {
        if sample.len() != self.channels {
            return Err(self.wrong_size(format!("{} strings", sample.len())));
        }
        let owned: Vec<CString> = sample
            .iter()
            .map(|s| c_string(&s.replace('\0', "")))
            .collect::<Result<_, _>>()?;
        let ptrs: Vec<*const c_char> = owned.iter().map(|s| s.as_ptr()).collect();
        // SAFETY: one C string per channel (checked above), each living through the call;
        // liblsl reads exactly that many and copies them.
        let ec = unsafe {
            (self.lib.fns.push_sample_strtp)(
                self.handle.as_ptr(),
                ptrs.as_ptr(),
                timestamp,
                i32::from(pushthrough),
            )
        };
        self.lib.check(ec)
    }

    /// `lsl_push_chunk_ftnp`: `timestamps.len()` samples of `data` (sample after sample, one
    /// value per channel), each with its own timestamp.
    pub fn push_chunk_f32(
        &self,
        data: &[f32],
        timestamps: &[f64],
        pushthrough: bool,
    ) -> Result<(), Fault> {
        if data.len() != timestamps.len() * self.channels {
            return Err(self.wrong_size(format!(
                "{} values for {} timestamps",
                data.len(),
                timestamps.len()
            )));
        }
        if timestamps.is_empty() {
            return Ok(());
        }
        // SAFETY: `data` holds `data.len()` values, whole samples, and `timestamps` one per
        // sample (checked above), which is what liblsl reads.
        let ec = unsafe {
            (self.lib.fns.push_chunk_ftnp)(
                self.handle.as_ptr(),
                data.as_ptr(),
                data.len() as c_ulong,
                timestamps.as_ptr(),
                i32::from(pushthrough),
            )
        };
        self.lib.check(ec)
    }

    pub fn have_consumers(&self) -> bool {
        // SAFETY: a live handle.
        unsafe { (self.lib.fns.have_consumers)(self.handle.as_ptr()) != 0 }
    }

    pub fn wait_for_consumers(&self, timeout: f64) -> bool {
        // SAFETY: a live handle.
        unsafe { (self.lib.fns.wait_for_consumers)(self.handle.as_ptr(), timeout) != 0 }
    }
}
