//! Flash, static RAM and stack: linker symbols and the painted stack (cortex-m-rt's
//! `paint-stack` fills the stack with [`PAINT`] at reset; [`paint_below`] repaints the free
//! part to measure one stretch alone).

/// The paint of a stack word never written since it was painted.
pub const PAINT: u32 = 0xCCCC_CCCC;
/// Flash origin of the memory.x linked (`qemu-mps2`: mps2-an386's flash at 0).
const FLASH_ORIGIN: usize = if cfg!(feature = "qemu-mps2") { 0 } else { 0x0800_0000 };
/// RAM origin (both memory.x files).
const RAM_ORIGIN: usize = 0x2000_0000;

extern "C" {
    static __sdata: u32;
    static __edata: u32;
    static __sidata: u32;
    static _stack_end: u32;
    static _stack_start: u32;
}

/// The current stack pointer.
#[inline(always)]
pub fn sp() -> usize {
    cortex_m::register::msp::read() as usize
}

/// The stack's top (its first byte above the stack).
pub fn stack_top() -> usize {
    core::ptr::addr_of!(_stack_start) as usize
}

/// Paints the free stack from its bottom to 32 bytes below the caller's stack pointer.
#[inline(always)]
pub fn paint_below() {
    let sp = sp();
    // SAFETY: the words between the stack's bottom and SP − 32 are not live (the stack grows
    // down; nothing below SP is in use on a single-threaded system without interrupts).
    unsafe {
        let mut p = core::ptr::addr_of!(_stack_end) as *mut u32;
        while (p as usize) < sp - 32 {
            core::ptr::write_volatile(p, PAINT);
            p = p.add(1);
        }
    }
}

/// Bytes of stack written below `sp` since it was painted.
pub fn used_below(sp: usize) -> usize {
    // SAFETY: reads words of the stack region below SP; volatile, no aliasing with live data.
    unsafe {
        let mut p = core::ptr::addr_of!(_stack_end);
        while (p as usize) < sp && core::ptr::read_volatile(p) == PAINT {
            p = p.add(1);
        }
        sp.saturating_sub(p as usize)
    }
}

/// Flash (vector table, text, rodata and data's load image) and static RAM (data, bss,
/// uninit), bytes.
pub fn flash_and_static() -> (usize, usize) {
    let sdata = core::ptr::addr_of!(__sdata) as usize;
    let edata = core::ptr::addr_of!(__edata) as usize;
    let sidata = core::ptr::addr_of!(__sidata) as usize;
    let bottom = core::ptr::addr_of!(_stack_end) as usize;
    (sidata + (edata - sdata) - FLASH_ORIGIN, bottom - RAM_ORIGIN)
}
