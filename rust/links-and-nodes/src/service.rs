//! Services (ln.h "services", docs/rust.md "Services"): [`ServiceClient`] calls a service with
//! owned request/response values, [`Provider`] serves one with a closure.  The types come from
//! `ln_generate --lang rust`: a [`Service`] per service md, a [`ServiceData`] per section, and
//! [`wire`] holds what their conversions to and from libln's C structs use.

use std::ffi::{c_char, c_int, c_void, CString};
use std::fmt;
use std::marker::PhantomData;
use std::mem::MaybeUninit;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::ptr;
use std::sync::{Arc, Mutex};

use crate::client::{cstring, Shared};
use crate::error::{Error, Result};
use crate::{check, sys, Client};

/// A service md: its name, layout hash, signature and section types (generated).
///
/// # Safety
///
/// `MD_NAME`, `LAYOUT_HASH` and `SIGNATURE` are ln_generate's for the md, and `Request` and
/// `Response` are its request and response sections.
pub unsafe trait Service: 'static {
    /// The md name, e.g. "robot/set_gains".
    const MD_NAME: &'static str;
    /// ln_generate's 64-bit layout hash of the md.
    const LAYOUT_HASH: u64;
    /// The md's signature (`request|response`), which libln's codec walks.
    const SIGNATURE: &'static str;
    /// The request section (owned form).
    type Request: ServiceData;
    /// The response section (owned form).
    type Response: ServiceData;
}

/// One section (or nested md) of a service: an owned Rust value and its C struct `Raw`.
///
/// # Safety
///
/// `Raw` is `#[repr(C, packed)]` with the exact C layout of the section (a dynamic field is a
/// `u32` count and a pointer), all zero bytes are a valid `Raw`, `to_raw` returns pointers
/// that stay valid while `self` and `keep` live, and `from_raw` reads no more than the
/// counted elements behind each pointer.
pub unsafe trait ServiceData: Sized + Send + 'static {
    /// The C struct libln reads and fills.
    type Raw: Copy + 'static;
    /// The C struct of `self`: its dynamic fields point into `self` or into `keep`.
    fn to_raw(&self, keep: &mut wire::Keep) -> Result<Self::Raw>;
    /// An owned copy of a C struct.
    ///
    /// # Safety
    ///
    /// Every pointer of `raw` (recursively) points to its counted elements (or the count is
    /// 0), valid for the duration of the call.
    unsafe fn from_raw(raw: &Self::Raw) -> Result<Self>;
}

/// What generated conversions use: counts, borrowed and copied dynamic data.
pub mod wire {
    use std::any::Any;
    use std::mem::size_of;
    use std::ptr;

    use super::ServiceData;
    use crate::error::{Error, Result};
    use crate::sys;

    /// Plain packed data of which every bit pattern is valid: primitives and generated
    /// structs without dynamic fields.
    ///
    /// # Safety
    ///
    /// The type has no padding, no pointers and no invalid bit patterns.
    pub unsafe trait Plain: Copy + Send + 'static {}

    macro_rules! plain {
        ($($t:ty),*) => { $(
            // SAFETY: primitive numbers: any bits are valid, no padding.
            unsafe impl Plain for $t {}
        )* };
    }
    plain!(u8, i8, u16, i16, u32, i32, u64, i64, f32, f64);

    /// Memory a request's C struct points into besides the owned value (converted nested
    /// records); kept until the call returns.
    #[derive(Default)]
    pub struct Keep(Vec<Box<dyn Any>>);

    impl Keep {
        /// An empty store.
        pub fn new() -> Keep {
            Keep(Vec::new())
        }
    }

    /// The `u32` count of a dynamic field of `n` elements.
    pub fn len(n: usize, field: &str) -> Result<u32> {
        u32::try_from(n).map_err(|_| {
            Error::with_detail(
                sys::LN_ETOOBIG,
                format!("field '{field}': {n} elements do not fit a u32 count").into(),
            )
        })
    }

    /// The C structs of nested records with dynamic fields, kept in `keep`.
    pub fn records_to_raw<T: ServiceData>(items: &[T], keep: &mut Keep) -> Result<*const T::Raw> {
        let raws = items
            .iter()
            .map(|item| item.to_raw(keep))
            .collect::<Result<Vec<T::Raw>>>()?;
        let p = raws.as_ptr();
        keep.0.push(Box::new(raws)); // moving the Vec keeps its buffer where it is
        Ok(p)
    }

    /// The C structs of a static array of records with dynamic fields.
    pub fn array_to_raw<T: ServiceData, const N: usize>(
        items: &[T; N],
        keep: &mut Keep,
    ) -> Result<[T::Raw; N]> {
        let raws = items
            .iter()
            .map(|item| item.to_raw(keep))
            .collect::<Result<Vec<T::Raw>>>()?;
        Ok(raws.try_into().unwrap_or_else(|_| unreachable!()))
    }

    /// Owned copies of a static array of C structs.
    ///
    /// # Safety
    ///
    /// As [`ServiceData::from_raw`] for each element.
    pub unsafe fn array_from_raw<T: ServiceData, const N: usize>(
        raws: &[T::Raw; N],
    ) -> Result<[T; N]> {
        let items = raws
            .iter()
            // SAFETY: the caller's promise, element by element.
            .map(|raw| unsafe { T::from_raw(raw) })
            .collect::<Result<Vec<T>>>()?;
        Ok(items.try_into().unwrap_or_else(|_| unreachable!()))
    }

    fn null_error() -> Error {
        Error::with_detail(
            sys::LN_EPROTOCOL,
            "a dynamic field has elements but a NULL pointer"
                .to_string()
                .into(),
        )
    }

    /// A copy of `n` plain elements at `p` (which need not be aligned).
    ///
    /// # Safety
    ///
    /// `p` points to `n` elements (or `n` is 0).
    pub unsafe fn vec_from_raw<T: Plain>(p: *const T, n: u32) -> Result<Vec<T>> {
        let n = n as usize;
        if n == 0 {
            return Ok(Vec::new());
        }
        if p.is_null() {
            return Err(null_error());
        }
        let mut out = Vec::<T>::with_capacity(n);
        // SAFETY: n elements are readable at p (caller); out has room for n; T is Plain, so
        // its bytes copied one by one make valid values without regard to p's alignment.
        unsafe {
            ptr::copy_nonoverlapping(
                p.cast::<u8>(),
                out.as_mut_ptr().cast::<u8>(),
                n * size_of::<T>(),
            );
            out.set_len(n);
        }
        Ok(out)
    }

    /// A `char*` field as a String: its `n` bytes must be UTF-8.
    ///
    /// # Safety
    ///
    /// As [`vec_from_raw`].
    pub unsafe fn string_from_raw(p: *const u8, n: u32, field: &str) -> Result<String> {
        // SAFETY: the caller's promise.
        let bytes = unsafe { vec_from_raw(p, n) }?;
        String::from_utf8(bytes).map_err(|e| {
            let at = e.utf8_error().valid_up_to();
            Error::with_detail(
                sys::LN_EINVAL,
                format!("field '{field}' is not UTF-8 (byte {at} of {n}); use uint8_t* for bytes")
                    .into(),
            )
        })
    }

    /// Owned copies of `n` nested C structs at `p` (which need not be aligned).
    ///
    /// # Safety
    ///
    /// `p` points to `n` records (or `n` is 0), each as [`ServiceData::from_raw`] requires.
    pub unsafe fn records_from_raw<T: ServiceData>(p: *const T::Raw, n: u32) -> Result<Vec<T>> {
        if n == 0 {
            return Ok(Vec::new());
        }
        if p.is_null() {
            return Err(null_error());
        }
        (0..n as usize)
            // SAFETY: element i of n is readable (caller); read_unaligned needs no alignment.
            .map(|i| unsafe { T::from_raw(&ptr::read_unaligned(p.add(i))) })
            .collect()
    }
}

/// The error answer of a provider's handler: the caller gets `Error::ESERVICE` with this text.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ServiceError(String);

impl ServiceError {
    /// An error answer with `text`.
    pub fn new(text: impl Into<String>) -> ServiceError {
        ServiceError(text.into())
    }

    /// The text the caller gets.
    pub fn text(&self) -> &str {
        &self.0
    }
}

impl fmt::Display for ServiceError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for ServiceError {}

impl From<String> for ServiceError {
    fn from(text: String) -> ServiceError {
        ServiceError(text)
    }
}

impl From<&str> for ServiceError {
    fn from(text: &str) -> ServiceError {
        ServiceError(text.to_string())
    }
}

impl From<Error> for ServiceError {
    fn from(e: Error) -> ServiceError {
        ServiceError(e.to_string())
    }
}

/// A caller's handle of one service (`ln_service`); see [`Client::service`].
///
/// Threads: `Send + Sync`; calls on one handle run one at a time (use one handle per thread
/// for parallel calls).
pub struct ServiceClient<S: Service> {
    shared: Arc<Shared>,
    raw: *mut sys::ln_service,
    /// One call at a time: the response memory is libln's until the next call.
    calls: Mutex<()>,
    name: String,
    _service: PhantomData<fn() -> S>,
}

// SAFETY: the handle is used only under `calls` and the client's gate.
unsafe impl<S: Service> Send for ServiceClient<S> {}
// SAFETY: as above.
unsafe impl<S: Service> Sync for ServiceClient<S> {}

/// The md arguments of ln_get_service / ln_get_service_provider.
fn md_args<S: Service>() -> Result<(CString, CString)> {
    Ok((
        cstring("md name", S::MD_NAME)?,
        cstring("signature", S::SIGNATURE)?,
    ))
}

impl<S: Service> ServiceClient<S> {
    /// Sends `request` and returns the response; `timeout` in seconds (< 0: forever).
    /// Errors: `ESERVICE` (the provider's error text as detail), `ENOTFOUND`, `ELAYOUT` (the
    /// provider has another layout), `ECONNECTION` (provider gone), `ETIMEOUT`, `ETOOBIG`.
    pub fn call(&self, request: &S::Request, timeout: f64) -> Result<S::Response> {
        let mut keep = wire::Keep::new();
        let raw_request = request.to_raw(&mut keep)?;
        let _one = self.calls.lock().unwrap_or_else(|e| e.into_inner());
        let _open = self.shared.enter()?;
        let mut response = MaybeUninit::<<S::Response as ServiceData>::Raw>::zeroed();
        // SAFETY: the handle is live (gate held); raw_request points into `request`/`keep`,
        // both alive; response has the response section's C layout (ServiceData).
        check(unsafe {
            sys::ln_service_call(
                self.raw,
                ptr::from_ref(&raw_request).cast::<c_void>(),
                response.as_mut_ptr().cast::<c_void>(),
                timeout,
            )
        })?;
        // SAFETY: libln filled the struct; its dynamic fields point into the handle's memory,
        // valid until the next call, which `calls` holds off until the copy is done.
        unsafe { S::Response::from_raw(&response.assume_init()) }
    }

    /// Largest request or response (wire bytes plus decoded dynamic data) of this handle.
    pub fn set_max_size(&self, max_bytes: usize) -> Result<()> {
        let _one = self.calls.lock().unwrap_or_else(|e| e.into_inner());
        let _open = self.shared.enter()?;
        // SAFETY: live handle (gate held).
        check(unsafe { sys::ln_service_set_max_size(self.raw, max_bytes) }).map(|_| ())
    }

    /// The service name.
    pub fn name(&self) -> &str {
        &self.name
    }
}

impl<S: Service> Drop for ServiceClient<S> {
    fn drop(&mut self) {
        // After close, ln_client_destroy released the handle itself.
        if let Ok((_open, _setup)) = self.shared.enter_setup() {
            // SAFETY: live handle, released once.
            unsafe { sys::ln_service_release(self.raw) };
        }
    }
}

/// Options of [`Client::provide_with`].
#[derive(Debug, Clone, Default)]
pub struct ProviderOptions {
    /// Service group (`None`: the default group); see [`Client::handle_service_requests`].
    pub group: Option<String>,
    /// Largest request or response in bytes (`None`: `LN_SERVICE_DEFAULT_MAX_SIZE`).
    pub max_size: Option<usize>,
}

type Handler<S> = dyn FnMut(<S as Service>::Request) -> std::result::Result<<S as Service>::Response, ServiceError>
    + Send;

struct HandlerState<S: Service> {
    handler: Mutex<Box<Handler<S>>>,
}

/// A provider's handle of one service (`ln_service_provider`); see [`Client::provide`].
/// Dropping it unregisters the service (waiting for a request it is handling elsewhere).
pub struct Provider<S: Service> {
    shared: Arc<Shared>,
    raw: *mut sys::ln_service_provider,
    state: Option<Box<HandlerState<S>>>,
    name: String,
}

// SAFETY: the handle is used only under the client's gate and setup lock.
unsafe impl<S: Service> Send for Provider<S> {}

impl<S: Service> Provider<S> {
    /// The service name.
    pub fn name(&self) -> &str {
        &self.name
    }
}

impl<S: Service> Drop for Provider<S> {
    fn drop(&mut self) {
        let Some(state) = self.state.take() else {
            return;
        };
        if let Ok((_open, _setup)) = self.shared.enter_setup() {
            // SAFETY: live handle, unregistered once; waits for a running handler.
            if unsafe { sys::ln_unregister_service_provider(self.raw) } >= 0 {
                return; // no handler can run any more: `state` is freed here
            }
        }
        // Closed client (it frees the provider when destroyed) or EBUSY (dropped inside its
        // own handler): a handler may still run, so the closure lives as long as the client.
        self.shared.keep_until_destroyed(state);
    }
}

/// Text for ln_service_request_respond_error (a NUL byte would end it early).
fn error_text(text: &str) -> CString {
    CString::new(text.replace('\0', "\\0")).unwrap_or_default()
}

fn respond_error(req: *mut sys::ln_service_request, text: &str) -> c_int {
    let text = error_text(text);
    // SAFETY: req is the live request of this handler call.
    unsafe { sys::ln_service_request_respond_error(req, text.as_ptr()) }
}

/// One request: decode, run the closure, answer.
fn handle<S: Service>(state: &HandlerState<S>, req: *mut sys::ln_service_request) -> c_int {
    let mut raw = MaybeUninit::<<S::Request as ServiceData>::Raw>::zeroed();
    // SAFETY: req is live during the handler; raw has the request section's C layout.
    let rc = unsafe { sys::ln_service_request_get_data(req, raw.as_mut_ptr().cast::<c_void>()) };
    if rc < 0 {
        return rc; // libln answers the error of the code
    }
    // SAFETY: libln filled it; its dynamic data lives until the handler returns.
    let request = match unsafe { S::Request::from_raw(&raw.assume_init()) } {
        Ok(r) => r,
        Err(e) => return respond_error(req, &format!("bad request: {e}")),
    };
    let answer = {
        let mut handler = state.handler.lock().unwrap_or_else(|e| e.into_inner());
        (*handler)(request)
    };
    match answer {
        Ok(response) => {
            let mut keep = wire::Keep::new();
            match response.to_raw(&mut keep) {
                // SAFETY: live request; the struct and what it points to outlive the call,
                // which encodes it at once.
                Ok(raw) => unsafe {
                    sys::ln_service_request_respond(req, ptr::from_ref(&raw).cast::<c_void>())
                },
                Err(e) => respond_error(req, &format!("bad response: {e}")),
            }
        }
        Err(e) => respond_error(req, e.text()),
    }
}

/// The `ln_service_handler` of a [`Provider`].  It takes no gate: it runs inside
/// `ln_wait_and_handle_service_group_requests` (which holds it) or on a pool thread that
/// `ln_client_destroy` joins (waiting for the gate there could deadlock with the destroy).
unsafe extern "C" fn trampoline<S: Service>(
    _clnt: *mut sys::ln_client,
    req: *mut sys::ln_service_request,
    user_data: *mut c_void,
) -> c_int {
    // SAFETY: user_data is the provider's HandlerState, alive while it is registered.
    let state = unsafe { &*user_data.cast::<HandlerState<S>>() };
    match catch_unwind(AssertUnwindSafe(|| handle::<S>(state, req))) {
        Ok(rc) => rc.min(0),
        Err(panic) => {
            let what = panic
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_default();
            let rc = respond_error(req, &format!("handler panicked: {what}"));
            if rc < 0 {
                sys::LN_ESERVICE
            } else {
                0
            }
        }
    }
}

fn group_cstring(group: Option<&str>) -> Result<Option<CString>> {
    group.map(|g| cstring("service group", g)).transpose()
}

fn opt_ptr(s: &Option<CString>) -> *const c_char {
    s.as_ref().map_or(ptr::null(), |s| s.as_ptr())
}

impl Client {
    /// A handle to call service `name` of md `S`; nothing is contacted until the first call.
    pub fn service<S: Service>(&self, name: &str) -> Result<ServiceClient<S>> {
        let c_name = cstring("service name", name)?;
        let (md, sig) = md_args::<S>()?;
        let (open, _setup) = self.shared().enter_setup()?;
        let mut raw = ptr::null_mut();
        // SAFETY: open client; strings live for the call (libln copies them).
        check(unsafe {
            sys::ln_get_service(
                open.raw(),
                &mut raw,
                c_name.as_ptr(),
                md.as_ptr(),
                S::LAYOUT_HASH,
                sig.as_ptr(),
            )
        })?;
        Ok(ServiceClient {
            shared: Arc::clone(self.shared()),
            raw,
            calls: Mutex::new(()),
            name: name.to_string(),
            _service: PhantomData,
        })
    }

    /// Provides service `name` of md `S` in the default group: `handler` answers each request
    /// (an `Err` is the caller's `ESERVICE`; a panic is caught and answered as an error).
    /// Requests are handled by [`Client::handle_service_requests`] or a thread pool
    /// ([`Client::handle_service_group_in_thread_pool`]); one at a time per provider.
    pub fn provide<S, F>(&self, name: &str, handler: F) -> Result<Provider<S>>
    where
        S: Service,
        F: FnMut(S::Request) -> std::result::Result<S::Response, ServiceError> + Send + 'static,
    {
        self.provide_with(name, &ProviderOptions::default(), handler)
    }

    /// [`Client::provide`] with a service group and a maximum message size.
    pub fn provide_with<S, F>(
        &self,
        name: &str,
        options: &ProviderOptions,
        handler: F,
    ) -> Result<Provider<S>>
    where
        S: Service,
        F: FnMut(S::Request) -> std::result::Result<S::Response, ServiceError> + Send + 'static,
    {
        let c_name = cstring("service name", name)?;
        let group = group_cstring(options.group.as_deref())?;
        let (md, sig) = md_args::<S>()?;
        let state: Box<HandlerState<S>> = Box::new(HandlerState {
            handler: Mutex::new(Box::new(handler)),
        });
        let (open, _setup) = self.shared().enter_setup()?;
        let mut raw = ptr::null_mut();
        // SAFETY: open client; strings copied by libln.
        check(unsafe {
            sys::ln_get_service_provider(
                open.raw(),
                &mut raw,
                c_name.as_ptr(),
                md.as_ptr(),
                S::LAYOUT_HASH,
                sig.as_ptr(),
            )
        })?;
        let user_data = ptr::from_ref::<HandlerState<S>>(&state)
            .cast_mut()
            .cast::<c_void>();
        // SAFETY: live provider; the state box outlives its registration (Provider's Drop).
        let setup = (|| unsafe {
            check(sys::ln_service_provider_set_handler(
                raw,
                Some(trampoline::<S>),
                user_data,
            ))?;
            if let Some(max) = options.max_size {
                check(sys::ln_service_provider_set_max_size(raw, max))?;
            }
            check(sys::ln_service_provider_register(raw, opt_ptr(&group)))
        })();
        if let Err(e) = setup {
            // SAFETY: the provider never served a request; freed once.
            unsafe { sys::ln_unregister_service_provider(raw) };
            return Err(e);
        }
        Ok(Provider {
            shared: Arc::clone(self.shared()),
            raw,
            state: Some(state),
            name: name.to_string(),
        })
    }

    /// Handles the requests of service group `group` (`None`: default) arriving within
    /// `timeout` seconds on this thread; returns how many were handled (0 on timeout).
    pub fn handle_service_requests(&self, group: Option<&str>, timeout: f64) -> Result<usize> {
        let group = group_cstring(group)?;
        let open = self.shared().enter()?;
        // SAFETY: open client (gate held for the whole wait).
        let n = check(unsafe {
            sys::ln_wait_and_handle_service_group_requests(open.raw(), opt_ptr(&group), timeout)
        })?;
        Ok(n as usize)
    }

    /// Hands group `group` (`None`: default) to thread pool `pool`: its threads handle the
    /// group's requests from now on, until the client is closed.
    pub fn handle_service_group_in_thread_pool(
        &self,
        group: Option<&str>,
        pool: &str,
    ) -> Result<()> {
        let group = group_cstring(group)?;
        let pool = cstring("thread pool", pool)?;
        let (open, _setup) = self.shared().enter_setup()?;
        // SAFETY: open client; strings copied by libln.
        check(unsafe {
            sys::ln_handle_service_group_in_thread_pool(open.raw(), opt_ptr(&group), pool.as_ptr())
        })
        .map(|_| ())
    }

    /// Maximum number of threads of thread pool `pool` (1 ..= 256).
    pub fn set_max_threads(&self, pool: &str, max_threads: u32) -> Result<()> {
        let pool = cstring("thread pool", pool)?;
        let (open, _setup) = self.shared().enter_setup()?;
        // SAFETY: open client.
        check(unsafe { sys::ln_set_max_threads(open.raw(), pool.as_ptr(), max_threads) })
            .map(|_| ())
    }
}
