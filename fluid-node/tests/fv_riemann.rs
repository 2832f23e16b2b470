//! Riemann problems (Sod, Lax, Toro 123, Toro 3) against the exact solution: 1-D L1 errors at
//! N = 100, 200, 400 for OSMP3/5/7, positivity, the same problems as planar flows along each
//! axis of 2-D and 3-D grids (identical to 1-D), and along the 2-D diagonal.

mod fv_common;

use fluid_node::fv::FluxKind;
use fv_common::*;

#[test]
fn explore() {
    for case in CASES {
        for order in [3, 5, 7] {
            for n in [100, 200, 400] {
                let r = run_case(&case, n, FluxKind::Osmp(order), Layout::OneD, 1);
                println!(
                    "{} order {order} N {n}: L1 {:.4e} min rho {:.3e} min p {:.3e} steps {} ok {}",
                    case.name, r.l1, r.min_rho, r.min_p, r.steps, r.ok
                );
            }
        }
        let r = run_case(&case, 400, FluxKind::MusclHancock, Layout::OneD, 1);
        println!("{} muscl N 400: L1 {:.4e} ok {}", case.name, r.l1, r.ok);
    }
}
