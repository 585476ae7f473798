//! [`ParameterBlock`]: typed parameters of a client that the manager's tools may override
//! (ln.h `ln_parameter_block*`, docs/parameters.md).  The block owns the input and output
//! arrays libln points into; the control loop calls `update()` (no allocation, no lock, no
//! system call in libln; here one uncontended gate load) and reads outputs by handle.
//!
//! Threads (ln.h): setup (create, add, register, drop) from one thread, `update()` and
//! `changed()` from the loop's thread: `ParameterBlock` is `Send` (built on one thread,
//! moved into the loop) but not `Sync`, and `update` takes `&mut self`.

use std::any::Any;
use std::ffi::{c_char, c_int, c_void, CStr};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::ptr;
use std::sync::Arc;

use crate::client::{cstring, Shared};
use crate::error::{Error, Result};
use crate::{check, sys, Client};
use std::mem::size_of;

mod sealed {
    pub trait Sealed {}
}

/// An md primitive a parameter can hold.
pub trait ParamType: Copy + Send + 'static + sealed::Sealed {
    /// Its md type name ("double", "int32_t", ...).
    const MD_TYPE: &'static str;
}

macro_rules! param_types {
    ($($t:ty => $name:literal),* $(,)?) => {$(
        impl sealed::Sealed for $t {}
        impl ParamType for $t {
            const MD_TYPE: &'static str = $name;
        }
    )*};
}

param_types!(
    i8 => "int8_t", u8 => "uint8_t", i16 => "int16_t", u16 => "uint16_t",
    i32 => "int32_t", u32 => "uint32_t", i64 => "int64_t", u64 => "uint64_t",
    f32 => "float", f64 => "double",
);

/// Checks and description of one parameter.
#[derive(Debug, Clone, Default)]
pub struct ParameterOptions {
    /// Shown by the tools.
    pub description: Option<String>,
    /// Every element must be >= min (`LN_PARAMETER_MIN`).
    pub min: Option<f64>,
    /// Every element must be <= max (`LN_PARAMETER_MAX`).
    pub max: Option<f64>,
    /// Shown by the tools, never overridden (`LN_PARAMETER_READ_ONLY`).
    pub read_only: bool,
}

/// The handle of one parameter of a block: read its value with [`ParameterBlock::get`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Param<T: ParamType> {
    index: c_int,
    block: usize,
    input: *mut T,
    output: *const T,
    count: usize,
}

// SAFETY: a handle is an index plus pointers only dereferenced by its own block (checked).
unsafe impl<T: ParamType> Send for Param<T> {}
// SAFETY: as above.
unsafe impl<T: ParamType> Sync for Param<T> {}

impl<T: ParamType> Param<T> {
    /// The parameter's index in its block.
    pub fn index(&self) -> usize {
        self.index as usize
    }
    /// Its number of elements.
    pub fn len(&self) -> usize {
        self.count
    }
    /// Whether it has no elements (never: a parameter has at least one).
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }
}

/// A parameter block of a client.  `Send`, not `Sync`; dropping it unregisters it.
pub struct ParameterBlock {
    shared: Arc<Shared>,
    raw: *mut sys::ln_parameter_block,
    /// The input and output arrays libln points into (boxed slices: stable addresses) and
    /// the installed validator.
    memory: Vec<Box<dyn Any + Send>>,
    /// Bytes of each parameter's value, by index (for the validator).
    sizes: Vec<usize>,
    validator: Option<Box<ValidatorFn>>,
}

type ValidatorFn = dyn Fn(&ParameterValue<'_>) -> std::result::Result<(), String> + Send + Sync;

/// A value about to be taken for a parameter, as the validator sees it.
#[derive(Debug)]
pub struct ParameterValue<'a> {
    index: usize,
    name: &'a str,
    bytes: &'a [u8],
}

impl ParameterValue<'_> {
    /// The parameter's index.
    pub fn index(&self) -> usize {
        self.index
    }
    /// The parameter's name.
    pub fn name(&self) -> &str {
        self.name
    }
    /// The value's elements if it is the value of `param` (same index), else `None`.
    pub fn get<T: ParamType>(&self, param: &Param<T>) -> Option<Vec<T>> {
        if param.index() != self.index || self.bytes.len() != param.count * size_of::<T>() {
            return None;
        }
        let mut out = Vec::with_capacity(param.count);
        for chunk in self.bytes.chunks_exact(size_of::<T>()) {
            // SAFETY: chunk holds size_of::<T>() bytes of an md primitive (any bits valid).
            out.push(unsafe { ptr::read_unaligned(chunk.as_ptr().cast::<T>()) });
        }
        Some(out)
    }
}

/// What libln's validator callback gets as user data.
struct Validator {
    check: Box<ValidatorFn>,
    sizes: Vec<usize>,
}

fn write_reason(reason: *mut c_char, size: usize, text: &str) {
    if reason.is_null() || size == 0 {
        return;
    }
    let n = text.len().min(size - 1);
    // SAFETY: reason has `size` writable bytes (ln.h); n + 1 <= size.
    unsafe {
        ptr::copy_nonoverlapping(text.as_ptr(), reason.cast::<u8>(), n);
        *reason.add(n) = 0;
    }
}

/// libln's validator callback: runs the Rust closure; a panic refuses the value and never
/// unwinds into C.
unsafe extern "C" fn validate(
    _blk: *mut sys::ln_parameter_block,
    index: c_int,
    name: *const c_char,
    value: *const c_void,
    reason: *mut c_char,
    reason_size: usize,
    user_data: *mut c_void,
) -> c_int {
    let outcome = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: user_data is the block's Validator, alive until the block is destroyed.
        let validator = unsafe { &*(user_data as *const Validator) };
        let size = usize::try_from(index)
            .ok()
            .and_then(|i| validator.sizes.get(i).copied())
            .unwrap_or(0);
        // SAFETY: name is NUL-terminated; value holds the parameter's count elements.
        let (name, bytes) = unsafe {
            (
                CStr::from_ptr(name).to_string_lossy(),
                std::slice::from_raw_parts(value.cast::<u8>(), size),
            )
        };
        (validator.check)(&ParameterValue {
            index: index as usize,
            name: &name,
            bytes,
        })
    }));
    match outcome {
        Ok(Ok(())) => 0,
        Ok(Err(text)) => {
            write_reason(reason, reason_size, &text);
            1
        }
        Err(_) => {
            write_reason(reason, reason_size, "the validator panicked");
            1
        }
    }
}

// SAFETY: ln.h: setup from one thread and update from the loop's thread; `&mut self` keeps
// both to one thread at a time, and the block lives as long as its client (`shared`).
unsafe impl Send for ParameterBlock {}

impl Client {
    /// A parameter block `name` (1..63 bytes of A-Z a-z 0-9 _ -); add parameters, then
    /// [`ParameterBlock::register`] it.
    pub fn parameter_block(&self, name: &str) -> Result<ParameterBlock> {
        let c_name = cstring("block name", name)?;
        let mut raw = ptr::null_mut();
        let (open, _setup) = self.shared().enter_setup()?;
        // SAFETY: the client is open (gate) and setup calls are serialized.
        check(unsafe { sys::ln_parameter_block_create(open.raw(), &mut raw, c_name.as_ptr()) })?;
        Ok(ParameterBlock {
            shared: Arc::clone(self.shared()),
            raw,
            memory: Vec::new(),
            sizes: Vec::new(),
            validator: None,
        })
    }
}

impl ParameterBlock {
    /// Adds parameter `name` with `value.len()` elements (its input: the value the program
    /// gives it without an override; change it with [`ParameterBlock::set_input`]).
    pub fn add<T: ParamType>(
        &mut self,
        name: &str,
        value: &[T],
        options: &ParameterOptions,
    ) -> Result<Param<T>> {
        if value.is_empty() {
            return Err(Error::with_detail(
                sys::LN_EINVAL,
                format!("parameter {name:?}: no elements").into(),
            ));
        }
        let c_name = cstring("parameter name", name)?;
        let c_type = cstring("type", T::MD_TYPE)?;
        let c_desc = match &options.description {
            Some(d) => Some(cstring("description", d)?),
            None => None,
        };
        let mut input: Box<[T]> = value.into();
        let mut output: Box<[T]> = value.into();
        let mut flags = 0;
        if options.min.is_some() {
            flags |= sys::LN_PARAMETER_MIN;
        }
        if options.max.is_some() {
            flags |= sys::LN_PARAMETER_MAX;
        }
        if options.read_only {
            flags |= sys::LN_PARAMETER_READ_ONLY;
        }
        let desc = sys::ln_parameter_desc {
            name: c_name.as_ptr(),
            type_: c_type.as_ptr(),
            count: value.len() as u32,
            flags,
            description: c_desc.as_ref().map_or(ptr::null(), |d| d.as_ptr()),
            input: input.as_mut_ptr().cast_const().cast(),
            output: output.as_mut_ptr().cast(),
            min: options.min.unwrap_or(0.0),
            max: options.max.unwrap_or(0.0),
        };
        let (_open, _setup) = self.shared.enter_setup()?;
        // SAFETY: the block is open; libln copies the strings and keeps input/output, which
        // live in `memory` until the block is destroyed.
        let index = check(unsafe { sys::ln_parameter_block_add(self.raw, &desc) })?;
        let param = Param {
            index,
            block: self.raw as usize,
            input: input.as_mut_ptr(),
            output: output.as_ptr(),
            count: value.len(),
        };
        self.sizes.push(std::mem::size_of_val(value));
        self.memory.push(Box::new(input));
        self.memory.push(Box::new(output));
        Ok(param)
    }

    /// Sets the check every value about to be taken must pass (after type, count, range and
    /// read-only): `Err(reason)` refuses it and the setter gets the reason.  It runs on
    /// libln's service thread (and, for `$LN_PARAMETERS`, in `register`); a panic in it
    /// refuses the value.  Installed by `register`, so set it before.
    pub fn set_validator<F>(&mut self, check: F)
    where
        F: Fn(&ParameterValue<'_>) -> std::result::Result<(), String> + Send + Sync + 'static,
    {
        self.validator = Some(Box::new(check));
    }

    /// Takes the initial overrides of `$LN_PARAMETERS` and registers the block's service:
    /// from now on the manager's tools may override its parameters.
    pub fn register(&mut self) -> Result<()> {
        let (_open, _setup) = self.shared.enter_setup()?;
        if let Some(checker) = self.validator.take() {
            let validator = Box::new(Validator {
                check: checker,
                sizes: self.sizes.clone(),
            });
            let user: *const Validator = &*validator;
            // the box's address stays as it moves into `memory`, freed after the block
            self.memory.push(validator);
            // SAFETY: the block is open; user lives as long as the block (memory).
            check(unsafe {
                sys::ln_parameter_block_set_validator(
                    self.raw,
                    Some(validate),
                    user.cast_mut().cast(),
                )
            })?;
        }
        // SAFETY: the block is open; setup calls serialized.
        check(unsafe { sys::ln_parameter_block_register(self.raw) }).map(|_| ())
    }

    /// The loop's update point: takes the overrides that arrived since the last call and
    /// writes every output.  Returns how many parameters changed their override.
    pub fn update(&mut self) -> Result<usize> {
        let _open = self.shared.enter()?;
        // SAFETY: the block is open; `&mut self`: no reader of the outputs meanwhile.
        let n = unsafe { sys::ln_parameter_block_update(self.raw) };
        if n < 0 {
            return Err(Error::from_code(n));
        }
        Ok(n as usize)
    }

    fn own<T: ParamType>(&self, param: &Param<T>) {
        assert_eq!(
            param.block, self.raw as usize,
            "parameter handle of another block"
        );
    }

    /// The value the program uses (the override, else the input) as of the last `update()`.
    /// Panics for a handle of another block.
    pub fn get<T: ParamType>(&self, param: &Param<T>) -> &[T] {
        self.own(param);
        // SAFETY: output has count elements owned by self.memory; only update (&mut self)
        // writes them.
        unsafe { std::slice::from_raw_parts(param.output, param.count) }
    }

    /// Sets the parameter's input (used whenever it has no override; visible after the next
    /// `update()`).  `Error::EINVAL` for another element count.
    pub fn set_input<T: ParamType>(&mut self, param: &Param<T>, value: &[T]) -> Result<()> {
        self.own(param);
        if value.len() != param.count {
            return Err(Error::with_detail(
                sys::LN_EINVAL,
                format!("{} values for {} elements", value.len(), param.count).into(),
            ));
        }
        // SAFETY: input has count elements owned by self.memory; libln reads it only in
        // update(), which needs &mut self.
        unsafe { ptr::copy_nonoverlapping(value.as_ptr(), param.input, param.count) };
        Ok(())
    }

    /// Whether the parameter's override changed (set or reset) in the last `update()`.
    pub fn changed<T: ParamType>(&self, param: &Param<T>) -> bool {
        self.own(param);
        match self.shared.enter() {
            // SAFETY: the block is open.
            Ok(_open) => unsafe { sys::ln_parameter_block_changed(self.raw, param.index) == 1 },
            Err(_) => false,
        }
    }

    /// The block's service name, "<client>.parameters.<block>".
    pub fn service_name(&self) -> Result<String> {
        let _open = self.shared.enter()?;
        // SAFETY: the block is open; the name is owned by it and copied here.
        let name = unsafe { CStr::from_ptr(sys::ln_parameter_block_service_name(self.raw)) };
        Ok(name.to_string_lossy().into_owned())
    }
}

impl Drop for ParameterBlock {
    fn drop(&mut self) {
        let memory = std::mem::take(&mut self.memory);
        if let Ok((_open, _setup)) = self.shared.enter_setup() {
            // SAFETY: the block is open and destroyed once; after it libln no longer points
            // into `memory`.
            unsafe { sys::ln_parameter_block_destroy(self.raw) };
            drop(memory);
        } else {
            // Closed: the client's destruction (now or later) frees the block.
            self.shared.keep_until_destroyed(Box::new(memory));
        }
    }
}

impl std::fmt::Debug for ParameterBlock {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ParameterBlock").finish_non_exhaustive()
    }
}
