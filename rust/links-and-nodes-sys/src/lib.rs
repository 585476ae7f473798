//! Raw FFI declarations of libln's public header `ln/ln.h`, one per exported function and
//! type, in the header's order.  Written by hand and kept in step with the header by
//! `tests/header.rs` (a function or type of ln.h without a declaration here, or with another
//! parameter count, fails it).  The error codes `LN_E*` and the macro `ln_errno_map!` are
//! generated from ln.h's `LN_ERRNO_MAP` by build.rs.  Everything here is `unsafe`; the
//! ownership and thread rules are ln.h's, quoted in docs/rust.md.
#![allow(non_camel_case_types)]

use std::ffi::{c_char, c_double, c_int, c_uint, c_void};
use std::marker::{PhantomData, PhantomPinned};

include!(concat!(env!("OUT_DIR"), "/ln_errors.rs"));

pub const LN_OK: c_int = 0;
pub const LN_VERSION_MAJOR: c_int = 0;
pub const LN_VERSION_MINOR: c_int = 1;

pub const LN_CLIENT_NO_RECONNECT: u32 = 0x1;
pub const LN_PUBLISH_WAIT_FOR_SUBSCRIBERS: u32 = 0x1;
pub const LN_SUBSCRIBE_UDP: u32 = 0x100;
pub const LN_SUBSCRIBE_TCP: u32 = 0x200;
pub const LN_DEFAULT_SPIN_US: u32 = 20;
pub const LN_SERVICE_DEFAULT_MAX_SIZE: usize = 16 << 20;
pub const LN_EVENT_MAX_NAME: usize = 160;
pub const LN_LOG_DEBUG: c_int = 10;
pub const LN_LOG_INFO: c_int = 20;
pub const LN_LOG_WARNING: c_int = 30;
pub const LN_LOG_ERROR: c_int = 40;
pub const LN_LOG_CRITICAL: c_int = 50;
pub const LN_LOG_TEXT_MAX: usize = 512;
pub const LN_EVENT_MAX_CONNECT_SIZE: usize = 1024;
pub const LN_EVENT_MAX_HANDLERS: usize = 256;
pub const LN_PARAMETER_MIN: u32 = 0x1;
pub const LN_PARAMETER_MAX: u32 = 0x2;
pub const LN_PARAMETER_READ_ONLY: u32 = 0x4;
pub const LN_PARAMETER_MAX_NAME: usize = 63;

macro_rules! opaque {
    ($($name:ident),* $(,)?) => {$(
        /// Opaque libln handle (only ever used behind a pointer).
        #[repr(C)]
        pub struct $name {
            _data: [u8; 0],
            _marker: PhantomData<(*mut u8, PhantomPinned)>,
        }
    )*};
}

opaque!(
    ln_client,
    ln_outport,
    ln_inport,
    ln_service,
    ln_service_provider,
    ln_service_request,
    ln_event,
    ln_event_handler,
    ln_event_request,
    ln_logger,
    ln_parameter_block,
    ln_waitset,
);

#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct ln_client_options {
    pub manager: *const c_char,
    pub argc: c_int,
    pub argv: *mut *mut c_char,
    pub timeout: c_double,
    pub flags: u32,
}

#[repr(C)]
#[derive(Debug, Clone, Copy, Default)]
pub struct ln_port_options {
    pub buffers: u32,
    pub flags: u32,
    pub spin_us: u32,
}

#[repr(C)]
#[derive(Debug, Clone, Copy, Default)]
pub struct ln_sample_info {
    pub seq: u64,
    pub timestamp_ns: i64,
    pub overruns: u64,
}

pub type ln_service_handler = Option<
    unsafe extern "C" fn(
        clnt: *mut ln_client,
        req: *mut ln_service_request,
        user_data: *mut c_void,
    ) -> c_int,
>;

pub type ln_event_handler_fn = Option<
    unsafe extern "C" fn(
        clnt: *mut ln_client,
        call: *mut ln_event_request,
        user_data: *mut c_void,
    ) -> c_int,
>;

#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct ln_event_result {
    pub handler: *const c_char,
    pub client: *const c_char,
    pub code: c_int,
    pub error: *const c_char,
    pub connect: *const c_void,
    pub reply: *const c_void,
}

pub type ln_event_filter =
    Option<unsafe extern "C" fn(connect: *const c_void, user_data: *mut c_void) -> c_int>;

#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct ln_parameter_desc {
    pub name: *const c_char,
    pub type_: *const c_char,
    pub count: u32,
    pub flags: u32,
    pub description: *const c_char,
    pub input: *const c_void,
    pub output: *mut c_void,
    pub min: c_double,
    pub max: c_double,
}

#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct ln_waitset_event {
    pub id: u32,
    pub kind: u32,
    pub events: u32,
    pub count: u32,
    pub user_data: *mut c_void,
}

pub type ln_parameter_validator = Option<
    unsafe extern "C" fn(
        blk: *mut ln_parameter_block,
        index: c_int,
        name: *const c_char,
        value: *const c_void,
        reason: *mut c_char,
        reason_size: usize,
        user_data: *mut c_void,
    ) -> c_int,
>;

extern "C" {
    // ---- errors, versions
    pub fn ln_strerror(code: c_int) -> *const c_char;
    pub fn ln_error_name(code: c_int) -> *const c_char;
    pub fn ln_error_count() -> c_int;
    pub fn ln_version() -> *const c_char;
    pub fn ln_version_check(major: c_int, minor: c_int) -> c_int;

    // ---- clients, topics
    pub fn ln_client_options_init(opts: *mut ln_client_options);
    pub fn ln_client_create(
        out: *mut *mut ln_client,
        name: *const c_char,
        opts: *const ln_client_options,
    ) -> c_int;
    pub fn ln_client_destroy(clnt: *mut ln_client) -> c_int;
    pub fn ln_client_name(clnt: *const ln_client) -> *const c_char;
    pub fn ln_last_error() -> *const c_char;
    pub fn ln_client_last_error(clnt: *const ln_client, text: *mut c_char, size: usize) -> c_int;
    pub fn ln_port_options_init(opts: *mut ln_port_options);
    pub fn ln_publish(
        clnt: *mut ln_client,
        out: *mut *mut ln_outport,
        topic: *const c_char,
        md_name: *const c_char,
        layout_hash: u64,
        message_size: usize,
        opts: *const ln_port_options,
    ) -> c_int;
    pub fn ln_subscribe(
        clnt: *mut ln_client,
        out: *mut *mut ln_inport,
        topic: *const c_char,
        md_name: *const c_char,
        layout_hash: u64,
        message_size: usize,
        opts: *const ln_port_options,
    ) -> c_int;
    pub fn ln_unpublish(port: *mut ln_outport) -> c_int;
    pub fn ln_unsubscribe(port: *mut ln_inport) -> c_int;
    pub fn ln_write(
        port: *mut ln_outport,
        data: *const c_void,
        size: usize,
        timeout: c_double,
    ) -> c_int;
    pub fn ln_write_loan(port: *mut ln_outport, data: *mut *mut c_void, timeout: c_double)
        -> c_int;
    pub fn ln_write_commit(port: *mut ln_outport) -> c_int;
    pub fn ln_write_abort(port: *mut ln_outport) -> c_int;
    pub fn ln_read(
        port: *mut ln_inport,
        data: *mut c_void,
        size: usize,
        timeout: c_double,
        info: *mut ln_sample_info,
    ) -> c_int;
    pub fn ln_read_borrow(
        port: *mut ln_inport,
        data: *mut *const c_void,
        timeout: c_double,
        info: *mut ln_sample_info,
    ) -> c_int;
    pub fn ln_read_release(port: *mut ln_inport) -> c_int;
    pub fn ln_outport_subscriber_count(port: *const ln_outport) -> c_int;
    pub fn ln_inport_publisher_count(port: *const ln_inport) -> c_int;
    pub fn ln_inport_overruns(port: *const ln_inport) -> u64;
    pub fn ln_inport_set_interruptible(port: *mut ln_inport, on: c_int) -> c_int;
    pub fn ln_inport_interrupt(port: *mut ln_inport) -> c_int;

    // ---- time
    pub fn ln_client_use_clock(clnt: *mut ln_client, topic: *const c_char) -> c_int;
    pub fn ln_now(clnt: *mut ln_client, ns: *mut i64) -> c_int;

    // ---- services: callers
    pub fn ln_get_service(
        clnt: *mut ln_client,
        out: *mut *mut ln_service,
        name: *const c_char,
        md_name: *const c_char,
        layout_hash: u64,
        signature: *const c_char,
    ) -> c_int;
    pub fn ln_service_call(
        svc: *mut ln_service,
        request: *const c_void,
        response: *mut c_void,
        timeout: c_double,
    ) -> c_int;
    pub fn ln_service_set_max_size(svc: *mut ln_service, max_bytes: usize) -> c_int;
    pub fn ln_service_release(svc: *mut ln_service) -> c_int;

    // ---- services: providers
    pub fn ln_get_service_provider(
        clnt: *mut ln_client,
        out: *mut *mut ln_service_provider,
        name: *const c_char,
        md_name: *const c_char,
        layout_hash: u64,
        signature: *const c_char,
    ) -> c_int;
    pub fn ln_service_provider_set_handler(
        provider: *mut ln_service_provider,
        handler: ln_service_handler,
        user_data: *mut c_void,
    ) -> c_int;
    pub fn ln_service_provider_set_max_size(
        provider: *mut ln_service_provider,
        max_bytes: usize,
    ) -> c_int;
    pub fn ln_service_provider_register(
        provider: *mut ln_service_provider,
        group: *const c_char,
    ) -> c_int;
    pub fn ln_unregister_service_provider(provider: *mut ln_service_provider) -> c_int;
    pub fn ln_wait_and_handle_service_group_requests(
        clnt: *mut ln_client,
        group: *const c_char,
        timeout: c_double,
    ) -> c_int;
    pub fn ln_handle_service_group_in_thread_pool(
        clnt: *mut ln_client,
        group: *const c_char,
        pool: *const c_char,
    ) -> c_int;
    pub fn ln_set_max_threads(
        clnt: *mut ln_client,
        pool: *const c_char,
        max_threads: c_uint,
    ) -> c_int;
    pub fn ln_service_request_get_data(req: *mut ln_service_request, request: *mut c_void)
        -> c_int;
    pub fn ln_service_request_respond(
        req: *mut ln_service_request,
        response: *const c_void,
    ) -> c_int;
    pub fn ln_service_request_respond_error(
        req: *mut ln_service_request,
        text: *const c_char,
    ) -> c_int;
    pub fn ln_service_request_service_name(req: *const ln_service_request) -> *const c_char;

    // ---- events
    pub fn ln_event_connect(
        clnt: *mut ln_client,
        out: *mut *mut ln_event_handler,
        event: *const c_char,
        md_name: *const c_char,
        layout_hash: u64,
        signature: *const c_char,
        connect: *const c_void,
        handler: ln_event_handler_fn,
        user_data: *mut c_void,
        group: *const c_char,
    ) -> c_int;
    pub fn ln_event_disconnect(handler: *mut ln_event_handler) -> c_int;
    pub fn ln_event_handler_name(handler: *const ln_event_handler) -> *const c_char;
    pub fn ln_event_request_get_data(call: *mut ln_event_request, data: *mut c_void) -> c_int;
    pub fn ln_event_request_reply(call: *mut ln_event_request, reply: *const c_void) -> c_int;
    pub fn ln_event_request_reply_error(call: *mut ln_event_request, text: *const c_char) -> c_int;
    pub fn ln_event_request_event_name(call: *const ln_event_request) -> *const c_char;
    pub fn ln_get_event(
        clnt: *mut ln_client,
        out: *mut *mut ln_event,
        event: *const c_char,
        md_name: *const c_char,
        layout_hash: u64,
        signature: *const c_char,
    ) -> c_int;
    pub fn ln_event_set_filter(
        ev: *mut ln_event,
        filter: ln_event_filter,
        user_data: *mut c_void,
    ) -> c_int;
    pub fn ln_event_call(ev: *mut ln_event, call: *const c_void, timeout: c_double) -> c_int;
    pub fn ln_event_result_count(ev: *const ln_event) -> c_int;
    pub fn ln_event_get_result(
        ev: *const ln_event,
        index: usize,
        out: *mut ln_event_result,
    ) -> c_int;
    pub fn ln_event_release(ev: *mut ln_event) -> c_int;

    // ---- manager commands, loggers
    pub fn ln_control(
        clnt: *mut ln_client,
        command: *const c_char,
        result: *mut *mut c_char,
    ) -> c_int;
    pub fn ln_free(p: *mut c_void);
    pub fn ln_logger_open(
        clnt: *mut ln_client,
        name: *const c_char,
        out: *mut *mut ln_logger,
    ) -> c_int;
    pub fn ln_logger_add_topic(
        lg: *mut ln_logger,
        topic: *const c_char,
        depth: u32,
        divisor: u32,
        span: c_double,
    ) -> c_int;
    pub fn ln_logger_enable(lg: *mut ln_logger) -> c_int;
    pub fn ln_logger_disable(lg: *mut ln_logger) -> c_int;
    pub fn ln_logger_save(lg: *mut ln_logger, path: *const c_char) -> c_int;
    pub fn ln_logger_close(lg: *mut ln_logger);

    // ---- client logging
    pub fn ln_log(clnt: *mut ln_client, level: c_int, fmt: *const c_char, ...) -> c_int;
    pub fn ln_log_at(
        clnt: *mut ln_client,
        level: c_int,
        file: *const c_char,
        line: c_int,
        fmt: *const c_char,
        ...
    ) -> c_int;
    pub fn ln_log_text(
        clnt: *mut ln_client,
        level: c_int,
        file: *const c_char,
        line: c_int,
        logger: *const c_char,
        text: *const c_char,
    ) -> c_int;
    pub fn ln_log_set_level(clnt: *mut ln_client, level: c_int) -> c_int;
    pub fn ln_log_counts(clnt: *mut ln_client, queued: *mut u64, dropped: *mut u64) -> c_int;
    pub fn ln_log_flush(clnt: *mut ln_client, timeout: f64) -> c_int;

    // ---- parameter blocks
    pub fn ln_parameter_block_create(
        clnt: *mut ln_client,
        out: *mut *mut ln_parameter_block,
        name: *const c_char,
    ) -> c_int;
    pub fn ln_parameter_block_add(
        blk: *mut ln_parameter_block,
        desc: *const ln_parameter_desc,
    ) -> c_int;
    pub fn ln_parameter_block_set_validator(
        blk: *mut ln_parameter_block,
        validator: ln_parameter_validator,
        user_data: *mut c_void,
    ) -> c_int;
    pub fn ln_parameter_block_register(blk: *mut ln_parameter_block) -> c_int;
    pub fn ln_parameter_block_update(blk: *mut ln_parameter_block) -> c_int;
    pub fn ln_parameter_block_changed(blk: *const ln_parameter_block, index: c_int) -> c_int;
    pub fn ln_parameter_block_service_name(blk: *const ln_parameter_block) -> *const c_char;
    pub fn ln_parameter_block_destroy(blk: *mut ln_parameter_block) -> c_int;

    // ---- the waitset
    pub fn ln_waitset_create(out: *mut *mut ln_waitset) -> c_int;
    pub fn ln_waitset_destroy(ws: *mut ln_waitset) -> c_int;
    pub fn ln_waitset_attach_inport(
        ws: *mut ln_waitset,
        port: *mut ln_inport,
        flags: u32,
        deadline: c_double,
        user_data: *mut c_void,
        id: *mut u32,
    ) -> c_int;
    pub fn ln_waitset_set_deadline(ws: *mut ln_waitset, id: u32, deadline: c_double) -> c_int;
    pub fn ln_waitset_attach_service_group(
        ws: *mut ln_waitset,
        clnt: *mut ln_client,
        group: *const c_char,
        user_data: *mut c_void,
        id: *mut u32,
    ) -> c_int;
    pub fn ln_waitset_attach_provider(
        ws: *mut ln_waitset,
        provider: *mut ln_service_provider,
        user_data: *mut c_void,
        id: *mut u32,
    ) -> c_int;
    pub fn ln_waitset_attach_event_handler(
        ws: *mut ln_waitset,
        handler: *mut ln_event_handler,
        user_data: *mut c_void,
        id: *mut u32,
    ) -> c_int;
    pub fn ln_waitset_attach_parameter_block(
        ws: *mut ln_waitset,
        blk: *mut ln_parameter_block,
        user_data: *mut c_void,
        id: *mut u32,
    ) -> c_int;
    pub fn ln_waitset_attach_fd(
        ws: *mut ln_waitset,
        fd: c_int,
        events: u32,
        user_data: *mut c_void,
        id: *mut u32,
    ) -> c_int;
    pub fn ln_waitset_attach_timer(
        ws: *mut ln_waitset,
        first_ns: i64,
        period: c_double,
        user_data: *mut c_void,
        id: *mut u32,
    ) -> c_int;
    pub fn ln_waitset_detach(ws: *mut ln_waitset, id: u32) -> c_int;
    pub fn ln_waitset_wait(
        ws: *mut ln_waitset,
        timeout: c_double,
        ready: *mut ln_waitset_event,
        n: usize,
    ) -> c_int;
    pub fn ln_waitset_trigger(ws: *mut ln_waitset) -> c_int;
    pub fn ln_waitset_fd(ws: *const ln_waitset) -> c_int;
    pub fn ln_waitset_next_due(ws: *mut ln_waitset, monotonic_ns: *mut i64) -> c_int;
}
