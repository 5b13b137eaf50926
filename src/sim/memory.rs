//! The contact-memory rule of MODEL.md §8.5 and §8.7 (the one copy: the simulator and the
//! diffsol comparison both call it).

/// Contact memory of one phalanx (§8.5): active between onset and separation.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Memory {
    /// Between onset and separation.
    pub active: bool,
    /// Captured onset velocity δ̇⁻ (floored at v_min).
    pub vminus: f64,
}

/// What an event did to a contact's memory.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MemoryChange {
    /// Nothing changed.
    Unchanged,
    /// The contact started: memory set, δ̇⁻ captured.
    Onset,
    /// The contact separated: memory cleared.
    Separation,
}

impl Memory {
    /// Contact event function: δ + ε_sep while active, δ otherwise.
    #[inline]
    pub fn event_value(&self, delta: f64, eps_sep: f64) -> f64 {
        if self.active {
            delta + eps_sep
        } else {
            delta
        }
    }

    /// The onset/separation rule at an event (`located`: this contact's own event was
    /// located here; the others change only when moving the right way, §8.7).
    /// Onset: !active && δ > 0 && (located || δ̇ > 0) → active, δ̇⁻ = max(δ̇, v_min).
    /// Separation: active && δ < −ε_sep && (located || δ̇ < 0) → cleared.
    #[inline]
    pub fn update(&mut self, delta: f64, delta_dot: f64, located: bool, eps_sep: f64, v_min: f64) -> MemoryChange {
        if !self.active && delta > 0.0 && (located || delta_dot > 0.0) {
            *self = Memory { active: true, vminus: delta_dot.max(v_min) };
            MemoryChange::Onset
        } else if self.active && delta < -eps_sep && (located || delta_dot < 0.0) {
            *self = Memory::default();
            MemoryChange::Separation
        } else {
            MemoryChange::Unchanged
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Onset and separation need δ strictly past the threshold and, for an unlocated
    /// contact, δ̇ moving the right way.
    #[test]
    fn onset_and_separation_rules() {
        let mut m = Memory::default();
        assert_eq!(m.update(0.0, 1.0, true, 1e-6, 1e-3), MemoryChange::Unchanged);
        assert_eq!(m.update(1e-9, -1.0, false, 1e-6, 1e-3), MemoryChange::Unchanged);
        assert_eq!(m.update(1e-9, 1e-5, true, 1e-6, 1e-3), MemoryChange::Onset);
        assert_eq!(m, Memory { active: true, vminus: 1e-3 });
        assert_eq!(m.event_value(-1e-6, 1e-6), 0.0);
        assert_eq!(m.update(-1e-6, -1.0, false, 1e-6, 1e-3), MemoryChange::Unchanged);
        assert_eq!(m.update(-2e-6, 1.0, false, 1e-6, 1e-3), MemoryChange::Unchanged);
        assert_eq!(m.update(-2e-6, 1.0, true, 1e-6, 1e-3), MemoryChange::Separation);
        assert_eq!(m, Memory::default());
    }
}
