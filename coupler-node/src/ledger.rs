//! The conservation ledger (DESIGN §3 step 6): the nodes' totals each step, the balance checked.
//!
//! Balances, with `0` the first report:
//! - mass: fluid mass plus the mass that left through open boundaries stays at its initial value
//!   (relative error, and absolute error to set against the mass the solid swept, the measure
//!   of paper 000 Fig. 11a, 21a and 28a);
//! - energy: Σ node energy (fluid total energy; solid kinetic + elastic + contact + gravity
//!   potential) + energy dissipated (links broken, contact dashpots and friction; less the work
//!   of the solid's prescribed motions, which put energy in) + energy that
//!   left through open boundaries stays at its initial value (relative error, and error
//!   relative to the largest energy exchanged through the interface, the measure of paper 003
//!   Fig. 7); the interface work moves energy between the nodes and cancels in the sum;
//! - interface: the work the fluid gives equals the work the solid receives.

use protocol::wire::ConservedTotals;
use serde::{Deserialize, Serialize};

/// One step's balance.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct LedgerEntry {
    /// The step just completed, counted from 0 as everywhere else (the `step` of the
    /// diagnostics and of the frames' stamps): the entry of the n-th step has `step` n − 1.
    /// The initial balance, taken before step 0, also has `step` 0 and is not recorded.
    pub step: u64,
    /// Time at its end \[s\].
    pub t: f64,
    /// Fluid mass \[kg\].
    pub fluid_mass: f64,
    /// Fluid total energy \[J\].
    pub fluid_energy: f64,
    /// Solid kinetic + potential (elastic, contact, gravity) energy \[J\].
    pub solid_energy: f64,
    /// Kinetic part of `solid_energy` (translation + rotation) \[J\].
    pub solid_kinetic: f64,
    /// Energy the solid dissipated \[J\]: elastic energy of its broken links, work of the
    /// contact dashpots and friction, less the work of its prescribed motions.
    pub solid_dissipated: f64,
    /// Energy dissipated, both nodes \[J\] (the fluid dissipates none it reports).
    pub dissipated: f64,
    /// |mass now − mass at start| / mass at start (0 when there is no mass).
    pub mass_rel_err: f64,
    /// |mass now − mass at start| \[kg\], the fluid mass counting what left through open
    /// boundaries (2-D: per unit depth).
    pub mass_abs_err: f64,
    /// Fluid mass the solid's motion displaced since the start \[kg\] (see
    /// [`ConservedTotals::swept_mass`]); `mass_abs_err / swept_mass` is paper 000's mass error.
    pub swept_mass: f64,
    /// |energy now − energy at start| / max(|energy at start|, largest |interface work|, largest
    /// magnitude of the energies' parts).
    pub energy_rel_err: f64,
    /// |energy now − energy at start| / largest |interface work| so far (0 without exchange).
    pub energy_err_vs_exchange: f64,
    /// Work given by the fluid through the interface \[J\].
    pub work_fluid: f64,
    /// Work received by the solid through the interface \[J\].
    pub work_solid: f64,
    /// Links broken so far.
    pub links_broken: u64,
    /// Solid sub-steps of the step (`run.solid_substeps`; 1 without it): a `ledger.csv` column
    /// only, neither in the diagnostics' JSON nor in the coupler's checkpoint.
    #[serde(skip)]
    pub solid_substeps: u32,
}

/// Header of `ledger.csv` (DESIGN §7).
pub const CSV_HEADER: [&str; 11] = [
    "t",
    "step",
    "fluid_mass",
    "fluid_energy",
    "solid_kinetic",
    "solid_elastic",
    "solid_dissipated",
    "interface_work",
    "mass_rel_err",
    "energy_rel_err",
    "solid_substeps",
];

impl LedgerEntry {
    /// The entry as one `ledger.csv` row, in the columns of [`CSV_HEADER`]: `solid_elastic` is
    /// the potential part of the solid's energy (`solid_energy` − `solid_kinetic`: elastic
    /// links, contacts, gravity), `interface_work` the work the solid received through the
    /// interface (`work_solid`; the fluid's side is `work_fluid` in the diagnostics). Numbers
    /// print in Rust's shortest round-trip form, so they parse back to the same bits.
    pub fn csv_record(&self) -> [String; 11] {
        let number = |x: f64| format!("{x:e}");
        [
            number(self.t),
            self.step.to_string(),
            number(self.fluid_mass),
            number(self.fluid_energy),
            number(self.solid_kinetic),
            number(self.solid_energy - self.solid_kinetic),
            number(self.solid_dissipated),
            number(self.work_solid),
            number(self.mass_rel_err),
            number(self.energy_rel_err),
            self.solid_substeps.max(1).to_string(),
        ]
    }
}

/// Running ledger.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Ledger {
    initial_mass: Option<f64>,
    initial_energy: Option<f64>,
    max_exchange: f64,
    max_scale: f64,
    /// Largest relative mass error seen.
    pub max_mass_rel_err: f64,
    /// Largest relative energy error seen.
    pub max_energy_rel_err: f64,
    /// Last entry.
    pub last: Option<LedgerEntry>,
}

fn energy_of(t: &ConservedTotals) -> f64 {
    t.energy + t.dissipated + t.boundary_energy_out
}

impl Ledger {
    /// Takes the totals of the nodes present at the end of `step` and returns the balance.
    /// Totals at step 0 before any motion should be reported first (`initial`).
    pub fn update(
        &mut self,
        step: u64,
        fluid: Option<&ConservedTotals>,
        solid: Option<&ConservedTotals>,
    ) -> LedgerEntry {
        let mass = fluid.map_or(0.0, |f| f.mass + f.boundary_mass_out);
        let energy = fluid.map_or(0.0, energy_of) + solid.map_or(0.0, energy_of);
        let initial_mass = *self.initial_mass.get_or_insert(mass);
        let initial_energy = *self.initial_energy.get_or_insert(energy);
        let work_fluid = fluid.map_or(0.0, |f| f.interface_work);
        let work_solid = solid.map_or(0.0, |s| s.interface_work);
        self.max_exchange = self
            .max_exchange
            .max(work_fluid.abs())
            .max(work_solid.abs());
        let mass_abs_err = (mass - initial_mass).abs();
        let mass_rel_err = if initial_mass != 0.0 {
            mass_abs_err / initial_mass.abs()
        } else {
            0.0
        };
        let energy_abs_err = (energy - initial_energy).abs();
        // NOTE: relative to the initial energy, or to the largest interface exchange, or to the
        // largest magnitude of the energies' parts, whichever is larger (a beam released under
        // gravity has a total energy near zero while kinetic and potential energy swap).
        let parts = fluid.map_or(0.0, |f| {
            f.energy_scale + f.dissipated.abs() + f.boundary_energy_out.abs()
        }) + solid.map_or(0.0, |s| s.energy_scale + s.dissipated.abs());
        self.max_scale = self.max_scale.max(parts);
        let scale = initial_energy
            .abs()
            .max(self.max_exchange)
            .max(self.max_scale);
        let energy_rel_err = if scale > 0.0 {
            energy_abs_err / scale
        } else {
            energy_abs_err
        };
        let energy_err_vs_exchange = if self.max_exchange > 0.0 {
            energy_abs_err / self.max_exchange
        } else {
            0.0
        };
        self.max_mass_rel_err = self.max_mass_rel_err.max(mass_rel_err);
        self.max_energy_rel_err = self.max_energy_rel_err.max(energy_rel_err);
        let entry = LedgerEntry {
            step,
            t: fluid.or(solid).map_or(0.0, |x| x.t),
            fluid_mass: fluid.map_or(0.0, |f| f.mass),
            fluid_energy: fluid.map_or(0.0, |f| f.energy),
            solid_energy: solid.map_or(0.0, |s| s.energy),
            solid_kinetic: solid.map_or(0.0, |s| s.kinetic),
            solid_dissipated: solid.map_or(0.0, |s| s.dissipated),
            dissipated: fluid.map_or(0.0, |f| f.dissipated) + solid.map_or(0.0, |s| s.dissipated),
            mass_rel_err,
            mass_abs_err,
            swept_mass: fluid.map_or(0.0, |f| f.swept_mass),
            energy_rel_err,
            energy_err_vs_exchange,
            work_fluid,
            work_solid,
            links_broken: solid.map_or(0, |s| s.links_broken),
            solid_substeps: 1,
        };
        self.last = Some(entry.clone());
        entry
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use protocol::wire::{NodeKind, Stamp};

    fn totals(node: NodeKind, mass: f64, energy: f64, out_m: f64, out_e: f64) -> ConservedTotals {
        ConservedTotals {
            stamp: Stamp::step(0),
            node,
            t: 0.0,
            mass,
            momentum: vec![0.0],
            energy,
            dissipated: 0.0,
            interface_work: 0.0,
            interface_impulse: vec![0.0],
            boundary_mass_out: out_m,
            boundary_energy_out: out_e,
            links_broken: 0,
            broken_pairs: Vec::new(),
            broken_substeps: Vec::new(),
            swept_mass: 0.0,
            vacuum_cells: 0,
            kinetic: 0.0,
            energy_scale: energy.abs(),
        }
    }

    #[test]
    fn energy_error_is_relative_to_the_parts_when_the_total_is_zero() {
        // A beam released under gravity: kinetic and potential energy cancel in the total.
        let mut ledger = Ledger::default();
        let mut s = totals(NodeKind::Solid, 10.0, 0.0, 0.0, 0.0);
        ledger.update(0, None, Some(&s));
        s.energy = 1e-3;
        s.energy_scale = 20.0;
        let e = ledger.update(1, None, Some(&s));
        assert!(
            (e.energy_rel_err - 5e-5).abs() < 1e-18,
            "{}",
            e.energy_rel_err
        );
    }

    #[test]
    fn a_csv_row_has_the_header_columns_and_parses_back_to_the_same_bits() {
        let mut ledger = Ledger::default();
        let mut s = totals(NodeKind::Solid, 3.0, 7.25, 0.0, 0.0);
        s.kinetic = 1.0 / 3.0;
        s.dissipated = 0.125;
        s.interface_work = -2.5e-7;
        s.t = 1.1e-4;
        let mut f = totals(NodeKind::Fluid, 2.0, 10.0, 0.0, 0.0);
        f.t = s.t;
        let e = ledger.update(4, Some(&f), Some(&s));
        let cells = e.csv_record();
        let value = |name: &str| -> f64 {
            let i = CSV_HEADER.iter().position(|n| *n == name).expect(name);
            cells[i].parse().expect(name)
        };
        assert_eq!(value("step"), 4.0);
        assert_eq!(value("t").to_bits(), 1.1e-4_f64.to_bits());
        assert_eq!(value("solid_kinetic").to_bits(), (1.0_f64 / 3.0).to_bits());
        // Potential = total − kinetic, to the rounding of one subtraction.
        assert!((value("solid_elastic") - (7.25 - 1.0 / 3.0)).abs() <= 1e-15 * 7.25);
        assert_eq!(value("solid_dissipated"), 0.125);
        assert_eq!(value("interface_work"), -2.5e-7);
        assert_eq!(value("fluid_mass"), 2.0);
    }

    #[test]
    fn boundary_outflow_is_not_an_error() {
        let mut ledger = Ledger::default();
        ledger.update(0, Some(&totals(NodeKind::Fluid, 2.0, 10.0, 0.0, 0.0)), None);
        let e = ledger.update(1, Some(&totals(NodeKind::Fluid, 1.5, 7.0, 0.5, 3.0)), None);
        assert_eq!(e.mass_rel_err, 0.0);
        assert_eq!(e.energy_rel_err, 0.0);
        let e = ledger.update(2, Some(&totals(NodeKind::Fluid, 1.5, 7.0, 0.25, 3.0)), None);
        assert!((e.mass_rel_err - 0.125).abs() < 1e-15, "{}", e.mass_rel_err);
        assert!((ledger.max_mass_rel_err - 0.125).abs() < 1e-15);
    }

    #[test]
    fn broken_links_and_contact_dissipation_close_the_energy_balance() {
        // Issue 14 item 4: fluid + solid (kinetic + elastic + contact) + dissipated is what
        // stays, and the interface work only moves energy between the nodes.
        let mut ledger = Ledger::default();
        let mut s = totals(NodeKind::Solid, 50.0, 5.0, 0.0, 0.0);
        s.kinetic = 2.0;
        let f = totals(NodeKind::Fluid, 1.0, 10.0, 0.0, 0.0);
        ledger.update(0, Some(&f), Some(&s));
        // A link breaks and releases its 2 J of elastic energy (3 → 1 J); then two fragments
        // touch: 0.5 J of kinetic energy goes to 0.3 J of contact potential and 0.2 J into the
        // dashpot. Meanwhile the fluid gives the solid 1 J through the interface.
        let mut f1 = f.clone();
        f1.energy = 9.0;
        f1.interface_work = 1.0;
        s.kinetic = 2.0 - 0.5 + 1.0;
        s.energy = s.kinetic + 1.0 + 0.3;
        s.dissipated = 2.0 + 0.2;
        s.interface_work = 1.0;
        s.energy_scale = s.energy;
        f1.energy_scale = f1.energy;
        s.links_broken = 1;
        let e = ledger.update(1, Some(&f1), Some(&s));
        assert!(e.energy_rel_err < 1e-15, "{}", e.energy_rel_err);
        assert_eq!(e.solid_dissipated, 2.2);
        assert_eq!(e.dissipated, 2.2);
        assert_eq!(e.links_broken, 1);
        // Without the dissipated energy the balance would miss 2.2 J of 15.
        s.dissipated = 0.0;
        let e = ledger.update(2, Some(&f1), Some(&s));
        assert!(
            (e.energy_rel_err - 2.2 / 15.0).abs() < 1e-15,
            "{}",
            e.energy_rel_err
        );
    }

    #[test]
    fn the_absolute_mass_error_and_the_swept_mass_are_reported() {
        let mut ledger = Ledger::default();
        ledger.update(0, Some(&totals(NodeKind::Fluid, 2.0, 10.0, 0.0, 0.0)), None);
        let mut f = totals(NodeKind::Fluid, 1.5 + 3e-13, 7.0, 0.5, 3.0);
        f.swept_mass = 0.25;
        let e = ledger.update(1, Some(&f), None);
        assert!((e.mass_abs_err - 3e-13).abs() < 1e-15, "{}", e.mass_abs_err);
        assert_eq!(e.swept_mass, 0.25);
        assert!((e.mass_rel_err - e.mass_abs_err / 2.0).abs() < 1e-30);
    }

    #[test]
    fn energy_moves_between_nodes() {
        let mut ledger = Ledger::default();
        let mut s = totals(NodeKind::Solid, 0.0, 1.0, 0.0, 0.0);
        ledger.update(
            0,
            Some(&totals(NodeKind::Fluid, 1.0, 4.0, 0.0, 0.0)),
            Some(&s),
        );
        s.energy = 2.0;
        s.interface_work = 1.0;
        let mut f = totals(NodeKind::Fluid, 1.0, 3.0, 0.0, 0.0);
        f.interface_work = 1.0;
        let e = ledger.update(1, Some(&f), Some(&s));
        assert_eq!(e.energy_rel_err, 0.0);
        assert_eq!((e.work_fluid, e.work_solid), (1.0, 1.0));
        s.energy = 2.5;
        let e = ledger.update(2, Some(&f), Some(&s));
        // Scale: the initial energy 5 (the parts' magnitudes reported never exceed it).
        assert!((e.energy_rel_err - 0.1).abs() < 1e-15);
        assert!((e.energy_err_vs_exchange - 0.5).abs() < 1e-15);
    }
}
