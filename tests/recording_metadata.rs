//! The `gripopt.run` metadata of a recording's shards: read into types (the shards of
//! 5d2a08e too, written back with the same keys), a missing or unreadable key named.

use crate::common::{copy_dir, recorded_fixture, scratch};
use std::path::Path;

/// Every metadata record (name, key → value) of the MCAP file `path`.
fn metadata_records(path: &Path) -> Vec<(String, std::collections::BTreeMap<String, String>)> {
    let buf = std::fs::read(path).unwrap();
    let summary = mcap::Summary::read(&buf).unwrap().unwrap();
    summary
        .metadata_indexes
        .iter()
        .map(|i| mcap::read::metadata(&buf, i).unwrap())
        .map(|m| (m.name, m.metadata))
        .collect()
}

/// Origin: issue 21 (session 37), gripopt's own files read into types; older versions still load.
#[test]
fn the_metadata_of_5d2a08e_shards_reads_into_run_metadata_and_writes_back_the_same_keys() {
    use gripopt::record::{RunMetadata, RUN_METADATA};
    let mut shards = 0;
    for run in ["centred", "free", "full"] {
        let rec = recorded_fixture(run).join("recording");
        for e in std::fs::read_dir(&rec).unwrap().flatten().filter(|e| e.path().extension() == Some("mcap".as_ref())) {
            for (name, map) in metadata_records(&e.path()) {
                assert_eq!(name, RUN_METADATA);
                let m = RunMetadata::from_map(&map).unwrap_or_else(|e| panic!("{run}: {e}"));
                assert!(m.epoch_s.is_some() && m.resolution.is_some() && m.first_id.flatten().is_some(), "{run}");
                // every key the type knows, each value as the old gripopt wrote it
                assert_eq!(m.to_map(), map, "{run}: {}", e.path().display());
                shards += 1;
            }
        }
    }
    assert!(shards >= 5, "the fixtures' shards were read ({shards})");
}

/// Origin: issue 21 (session 37), gripopt's own files read into types; older versions still load.
#[test]
fn a_missing_or_unreadable_metadata_key_is_named() {
    use gripopt::record::RunMetadata;
    use gripopt::Resolution;
    let map = |kv: &[(&str, &str)]| kv.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect();
    let m = RunMetadata::from_map(&map(&[("resolution", "full")])).unwrap();
    assert_eq!(m.resolution, Some(Resolution::Full));
    let e = m.require_epoch_s().unwrap_err();
    assert!(e.contains("`epoch_s`") && e.contains("missing"), "{e}");
    let e = RunMetadata::from_map(&map(&[("epoch_s", "12")])).unwrap().require_resolution().unwrap_err();
    assert!(e.contains("`resolution`") && e.contains("missing"), "{e}");
    let e = RunMetadata::from_map(&map(&[("resolution", "coarse")])).unwrap_err();
    assert!(e.contains("`resolution`") && e.contains("coarse"), "{e}");
    let e = RunMetadata::from_map(&map(&[("first_id", "-3")])).unwrap_err();
    assert!(e.contains("`first_id`") && e.contains("-3"), "{e}");
    let e = RunMetadata::from_map(&map(&[("scenario_object", "can"), ("scenario_index", "2")])).unwrap_err();
    assert!(e.contains("`object_grasp_height`") && e.contains("missing"), "{e}");
    // the resolution's words, both ways
    for r in [Resolution::Full, Resolution::Compact] {
        assert_eq!(r.to_string().parse::<Resolution>(), Ok(r));
        assert_eq!(serde_json::to_value(r).unwrap(), r.to_string().as_str(), "the word run.json uses");
    }
}

/// Origin: issue 21 (session 37), gripopt's own files read into types; older versions still load.
#[test]
fn a_shard_without_its_epoch_is_refused_naming_the_key() {
    // a 5d2a08e shard whose metadata record loses `epoch_s`: replay names the key
    let d = scratch("no-epoch");
    copy_dir(&recorded_fixture("centred"), &d);
    let shard = d.join("recording/gen-00001.mcap");
    let bytes = std::fs::read(&shard).unwrap();
    // rename the key in place (same length, so the file stays a valid MCAP)
    let at = bytes.windows(7).position(|w| w == b"epoch_s").unwrap();
    let mut edited = bytes.clone();
    edited[at..at + 7].copy_from_slice(b"epoch_t");
    std::fs::write(&shard, edited).unwrap();
    let e = gripopt::record::read_design(&d, 0).unwrap_err().to_string();
    assert!(e.contains("`epoch_s`") && e.contains("gen-00001.mcap"), "{e}");
}
