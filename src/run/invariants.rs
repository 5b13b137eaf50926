//! What a checkpoint must hold whatever its checksum says (`resume --force` overrides a
//! checksum, never these): design ids unique and below `next_id` (a design's id is its
//! identity in the recording, the tables and `show`'s commands: a reset `next_id` would
//! hand out an id twice), designs created no later than the checkpoint's generation, and
//! design vectors of one length of finite numbers (the optimiser's operators index them);
//! and, for a run to continue, the id budget: `next_id` plus the evaluations still to come
//! within the recording's clock ([`super::limits::MAX_EVALUATIONS`]); the reported front's
//! ids (the archive's `front`, pareto.csv) ascending, each an archive member's, at most the
//! population size.

use super::archive::Archive;
use crate::optim::{Individual, Nsga2State};
use crate::{Error, Result};
use std::path::Path;

/// Check the invariants of the state `st` and `archive` of the checkpoint read from `path`
/// (see the module doc); an error names the file and the field.
pub(crate) fn check_invariants<I>(st: &Nsga2State<I>, archive: Option<&Archive<I>>, path: &Path) -> Result<()> {
    let bad = |message: String| Error::Checkpoint { file: path.to_path_buf(), message };
    if st.next_id > super::limits::MAX_EVALUATIONS {
        return Err(bad(format!(
            "field `state.next_id` = {}: above the largest design id a recording holds ({}: ids are 1 s windows of a u64 nanosecond clock); the file was edited or damaged — restore this run's checkpoint.json",
            st.next_id,
            super::limits::MAX_EVALUATIONS
        )));
    }
    if let Some(front) = archive.and_then(|a| a.front.as_ref().map(|f| (f, &a.members))) {
        check_front(front, st.population.len()).map_err(&bad)?;
    }
    let archive = archive.map_or(&[][..], |a| &a.members[..]);
    // the run's vector length: the one most designs have (an edited design is the odd one)
    let mut lengths: Vec<usize> = st.population.iter().chain(archive).map(|m| m.x.len()).collect();
    lengths.sort_unstable();
    let mode = lengths.chunk_by(|a, b| a == b).max_by_key(|c| c.len()).map(|c| c[0]);
    let mut len = mode;
    for (field, members) in [("state.population", &st.population[..]), ("archive.members", archive)] {
        let mut ids: Vec<u64> = members.iter().map(|m| m.id).collect();
        ids.sort_unstable();
        if let Some(w) = ids.windows(2).find(|w| w[0] == w[1]) {
            return Err(bad(format!("field `{field}`: design id {} appears twice; ids are unique within a run (the file was edited or damaged)", w[0])));
        }
        for (k, m) in members.iter().enumerate() {
            check_member(m, k, field, st.next_id, st.generation, &mut len).map_err(&bad)?;
        }
    }
    Ok(())
}

/// The reported front's ids `front` against the archive's `members` and the population size
/// `pop`: ascending, each a member's, at most `pop` of them.
fn check_front<I>((front, members): (&Vec<u64>, &Vec<Individual<I>>), pop: usize) -> std::result::Result<(), String> {
    let at = "field `archive.front`";
    if front.len() > pop {
        return Err(format!(
            "{at}: {} ids, more than the population's {pop} (the file was edited or damaged)",
            front.len()
        ));
    }
    if let Some(w) = front.windows(2).find(|w| w[0] >= w[1]) {
        return Err(format!("{at}: ids not ascending ({} before {}; the file was edited or damaged)", w[0], w[1]));
    }
    let mut ids: Vec<u64> = members.iter().map(|m| m.id).collect();
    ids.sort_unstable();
    match front.iter().find(|id| ids.binary_search(id).is_err()) {
        Some(id) => Err(format!("{at}: design id {id} is not in `archive.members` (the file was edited or damaged)")),
        None => Ok(()),
    }
}

/// One design `m` (index `k` of `field`) against `next_id`, the checkpoint's `generation`
/// and the vector length of the designs before it (`len`).
fn check_member<I>(
    m: &Individual<I>,
    k: usize,
    field: &str,
    next_id: u64,
    generation: u64,
    len: &mut Option<usize>,
) -> std::result::Result<(), String> {
    let at = format!("field `{field}[{k}]` (design id {})", m.id);
    if m.id >= next_id {
        return Err(format!("{at}: id not below `state.next_id` = {next_id}: the next design would take an id already given (a reset or edited next_id); restore this run's checkpoint.json"));
    }
    if m.generation == 0 || m.generation > generation {
        return Err(format!(
            "{at}: `generation` = {} outside 1..={generation} (the checkpoint's generation)",
            m.generation
        ));
    }
    let want = *len.get_or_insert(m.x.len());
    if m.x.is_empty() || m.x.len() != want {
        return Err(format!("{at}: `x` has {} numbers where the run's designs have {want}", m.x.len()));
    }
    if let Some(v) = m.x.iter().find(|v| !v.is_finite()) {
        return Err(format!("{at}: `x` holds {v}, not a finite number"));
    }
    Ok(())
}

/// Check that the designs of a checkpoint's state `st` and `archive` (read from `path`) have
/// `n` numbers each (a gripper design: six); an error names the file and the first design
/// that has not.
pub(crate) fn check_design_length<I>(
    st: &Nsga2State<I>,
    archive: Option<&Archive<I>>,
    path: &Path,
    n: usize,
) -> Result<()> {
    let archive = archive.map_or(&[][..], |a| &a.members[..]);
    let members = st.population.iter().map(|m| ("state.population", m));
    let mut all = members.chain(archive.iter().map(|m| ("archive.members", m)));
    match all.find(|(_, m)| m.x.len() != n) {
        Some((field, m)) => Err(Error::Checkpoint {
            file: path.to_path_buf(),
            message: format!(
                "field `{field}` (design id {}): `x` has {} numbers; a design has {n} (l21, b, t22, r, p, psi_deg)",
                m.id,
                m.x.len()
            ),
        }),
        None => Ok(()),
    }
}

/// Check the id budget of continuing the checkpoint state `st` (read from `path`, population
/// `pop`) to `total` generations: its `next_id` plus a population's evaluations per
/// remaining generation within the recording's clock.
pub(crate) fn check_id_budget<I>(st: &Nsga2State<I>, pop: usize, path: &Path, total: u64) -> Result<()> {
    let remaining = total.saturating_sub(st.generation) as u128 * pop as u128;
    let last = st.next_id as u128 + remaining;
    if last > super::limits::MAX_EVALUATIONS as u128 {
        return Err(Error::Checkpoint {
            file: path.to_path_buf(),
            message: format!(
                "field `state.next_id` = {}: {remaining} more evaluations ({} generations of {}) would give ids up to {last}, beyond the recording's clock ({} ids); restore this run's checkpoint.json, or resume with fewer --generations",
                st.next_id,
                total.saturating_sub(st.generation),
                pop,
                super::limits::MAX_EVALUATIONS
            ),
        });
    }
    Ok(())
}
