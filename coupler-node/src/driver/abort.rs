//! What the supervisor tells the coupler's loop while it waits: stop, why, and which nodes'
//! processes ended.

use std::sync::{Arc, Mutex, MutexGuard};

use protocol::wire::NodeKind;

/// What the supervisor can tell the loop while it waits.
#[derive(Clone, Debug, Default)]
pub struct Abort(Arc<Mutex<Raised>>);

#[derive(Debug, Default)]
struct Raised {
    /// Why the loop is to stop; the first reason raised.
    reason: Option<String>,
    /// The nodes whose process ended before the run did: no shutdown is sent to them.
    exited: Vec<NodeKind>,
}

impl Abort {
    /// Asks the loop to stop with `reason`; the first reason raised is the one kept (both nodes
    /// failing at their start raise one each, and the status named the first node to exit with
    /// the second's reason).
    pub fn raise(&self, reason: String) {
        self.lock().reason.get_or_insert(reason);
    }

    /// [`Abort::raise`] for the process of `node`, which ended before the run did.
    pub fn node_exited(&self, node: NodeKind, reason: String) {
        let mut raised = self.lock();
        raised.exited.push(node);
        raised.reason.get_or_insert(reason);
    }

    /// Whether the process of `node` ended before the run did.
    pub(super) fn has_exited(&self, node: NodeKind) -> bool {
        self.lock().exited.contains(&node)
    }

    pub(super) fn check(&self) -> Option<String> {
        self.lock().reason.clone()
    }

    fn lock(&self) -> MutexGuard<'_, Raised> {
        self.0
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The first reason raised is the one the loop stops with; a node named exited is not sent
    /// a shutdown, the others are.
    #[test]
    fn an_abort_keeps_its_first_reason_and_the_nodes_that_exited() {
        let abort = Abort::default();
        assert_eq!(abort.check(), None);
        abort.node_exited(NodeKind::Solid, "solid node exited".into());
        abort.node_exited(NodeKind::Fluid, "fluid node exited".into());
        abort.raise("interrupted".into());
        assert_eq!(abort.check().as_deref(), Some("solid node exited"));
        assert!(abort.has_exited(NodeKind::Solid) && abort.has_exited(NodeKind::Fluid));
        let other = Abort::default();
        other.raise("interrupted".into());
        other.node_exited(NodeKind::Fluid, "fluid node exited".into());
        assert_eq!(other.check().as_deref(), Some("interrupted"));
        assert!(other.has_exited(NodeKind::Fluid) && !other.has_exited(NodeKind::Solid));
    }
}
