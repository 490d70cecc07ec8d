//! The boolean operation allocates nothing but its output for small inputs: one vector of
//! contours and one point vector per contour. Counted with a wrapping global allocator, only on
//! the test's own thread.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use arealight::glam::DVec2;
use arealight::planar::{BoolOp, Shape, boolean};

struct Counting;

thread_local! {
    static COUNTING: Cell<bool> = const { Cell::new(false) };
    static COUNT: Cell<usize> = const { Cell::new(0) };
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if COUNTING.with(Cell::get) {
            COUNT.with(|c| c.set(c.get() + 1));
        }
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if COUNTING.with(Cell::get) {
            COUNT.with(|c| c.set(c.get() + 1));
        }
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn ngon(n: usize, c: DVec2, r: f64, phase: f64) -> Shape {
    Shape::new(vec![
        (0..n)
            .map(|k| {
                let t = phase + std::f64::consts::TAU * k as f64 / n as f64;
                c + DVec2::new(t.cos(), t.sin()) * r
            })
            .collect(),
    ])
    .unwrap()
}

#[test]
fn only_the_output_is_allocated_for_small_inputs() {
    let cases = [
        (
            ngon(4, DVec2::ZERO, 1.0, 0.0),
            ngon(3, DVec2::new(0.5, 0.2), 0.8, 0.3),
        ),
        (
            ngon(8, DVec2::ZERO, 1.0, 0.0),
            ngon(8, DVec2::new(0.37, 0.21), 1.0, 0.13),
        ),
        (
            ngon(12, DVec2::ZERO, 1.0, 0.0),
            ngon(3, DVec2::ZERO, 0.3, 0.0),
        ), // hole in the middle
        (
            ngon(16, DVec2::ZERO, 1.0, 0.0),
            ngon(16, DVec2::new(0.37, 0.21), 1.0, 0.13),
        ),
    ];
    for (a, b) in &cases {
        for op in [
            BoolOp::Intersection,
            BoolOp::Union,
            BoolOp::Difference,
            BoolOp::Xor,
        ] {
            COUNT.with(|c| c.set(0));
            COUNTING.with(|c| c.set(true));
            let r = boolean(a, b, op);
            COUNTING.with(|c| c.set(false));
            let r = r.unwrap();
            let allocs = COUNT.with(Cell::get);
            let contours = r.contours().count();
            // One Vec<Contour> (grows at most once past four contours) plus one Vec per contour.
            let budget = contours + 1 + usize::from(contours > 4);
            assert!(
                allocs <= budget,
                "{op:?}: {allocs} allocations for {contours} output contours"
            );
            // The counter does see the output's own allocations.
            assert!(allocs >= contours, "{op:?}: counter missed allocations");
            assert!(r.area() > 0.0);
        }
    }
}
