//! [`Message`]: what a topic's sample type promises, implemented by the types
//! `ln_generate --lang rust` emits (or, for tests, written by hand beside their md).

/// A message type of an md: the plain bytes of one sample in a topic's ring.
///
/// # Safety
///
/// The implementor guarantees that the type is `#[repr(C, packed)]` (ln_generate's C
/// structs are `#pragma pack(1)`: no padding anywhere) with exactly the fields of md
/// `MD_NAME` in order, so `size_of::<Self>()` is the md's message size, that
/// `LAYOUT_HASH` is ln_generate's layout hash of that md, and that every bit pattern is a
/// valid value (fields are integers, floats, `u8`/`i8` chars and arrays or nested packed
/// structs of them: no `bool`, `char`, enums, references or pointers).  libln copies and
/// lends samples as raw bytes on that promise.
pub unsafe trait Message: Copy + Send + 'static {
    /// The md name, e.g. "robot/joint_state".
    const MD_NAME: &'static str;
    /// ln_generate's 64-bit layout hash of the md (`NAME_MD`'s hash in C).
    const LAYOUT_HASH: u64;
}
