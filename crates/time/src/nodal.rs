//! The explicit step's nodal friction: contact's closed form
//! ([`NodalClosedForm`], its constants formed once per Δt for D =
//! M_L/(γΔt)) fed with K r_K at the contact DOFs, formed here because only
//! this crate knows the step's K·x product.

use stickslip_contact::{ContactSurface, NodalClosedForm};
use stickslip_linalg::Formed;

/// The closed-form nodal friction of the explicit step and a slot per
/// contact DOF for K r_K there.
#[derive(Clone, Debug, Default)]
pub(crate) struct NodalFriction {
    closed_form: NodalClosedForm,
    /// K r_K at `closed_form.dofs()` ([`NodalFriction::products`]).
    ku: Vec<f64>,
}

impl NodalFriction {
    /// Forms the constants for D = `mass`·`scale` unless they are formed
    /// for this scale already.
    pub(crate) fn prepare(&mut self, contact: &ContactSurface, mass: &[f64], scale: f64) {
        self.closed_form.prepare(contact, mass, scale);
        self.ku.resize(self.closed_form.dofs().len(), 0.0);
    }

    /// K x (formed) at the contact nodes' free DOFs, with the bits the product's
    /// batches give them: `b`'s k-th call in [`NodalClosedForm::velocities`]
    /// is for `self.products()[k]`. [`NodalFriction::prepare`] first.
    pub(crate) fn form_products(&mut self, k: &Formed) {
        k.rows(self.closed_form.dofs(), &mut self.ku);
    }

    /// What [`NodalFriction::form_products`] formed.
    pub(crate) fn products(&self) -> &[f64] {
        &self.ku
    }

    /// The closed form, for its velocities and ledger.
    pub(crate) fn closed_form(&self) -> &NodalClosedForm {
        &self.closed_form
    }
}
