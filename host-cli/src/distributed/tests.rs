use super::*;
use std::collections::HashMap;

#[test]
fn ranges_parse_half_open_and_refuse_empty_or_reversed() {
    assert_eq!(PassRange::parse("0..4"), Ok(PassRange { start: 0, end: 4 }));
    assert_eq!(PassRange::parse(" 7 .. 9 "), Ok(PassRange { start: 7, end: 9 }));
    for bad in ["4..4", "5..2", "3", "a..b", "-1..3", "0..4294967296", "..3"] {
        assert!(PassRange::parse(bad).is_err(), "{bad}");
    }
}

/// Task shares cover 0..total once, in order, the first total mod count one longer.
#[test]
fn task_shares_tile_the_total_with_remainders_first() {
    for total in [1u32, 7, 10, 64, 1001] {
        for count in 1..=total.min(13) {
            let ranges: Vec<PassRange> = (0..count).map(|i| PassRange::of_task(i, count, total).unwrap()).collect();
            assert_eq!(ranges[0].start, 0);
            assert_eq!(ranges[count as usize - 1].end, total);
            for w in ranges.windows(2) {
                assert_eq!(w[0].end, w[1].start, "{total} / {count}");
                assert!(w[0].len() == w[1].len() || w[0].len() == w[1].len() + 1);
            }
        }
    }
    assert_eq!(PassRange::of_task(1, 4, 10), Ok(PassRange { start: 3, end: 6 }));
    assert_eq!(PassRange::of_task(3, 4, 10), Ok(PassRange { start: 8, end: 10 }));
    assert!(PassRange::of_task(4, 4, 10).is_err());
    assert!(PassRange::of_task(0, 5, 4).unwrap_err().contains("cannot share"));
}

fn env<'a>(pairs: &'a [(&'a str, &'a str)]) -> impl Fn(&str) -> Option<String> + 'a {
    let map: HashMap<&str, &str> = pairs.iter().copied().collect();
    move |k| map.get(k).map(|v| v.to_string())
}

#[test]
fn task_index_comes_from_slurm_or_kubernetes_and_never_silently() {
    let slurm = [("SLURM_ARRAY_TASK_ID", "12"), ("SLURM_ARRAY_TASK_MIN", "10"), ("SLURM_ARRAY_TASK_COUNT", "4")];
    assert_eq!(task_from_env(env(&slurm), None), Ok((2, 4)));
    assert_eq!(task_from_env(env(&slurm), Some(4)), Ok((2, 4)));
    assert!(task_from_env(env(&slurm), Some(5)).unwrap_err().contains("disagrees"));
    // A stepped array (--array=0-12:4) has ids past min + count.
    let stepped = [("SLURM_ARRAY_TASK_ID", "12"), ("SLURM_ARRAY_TASK_MIN", "0"), ("SLURM_ARRAY_TASK_COUNT", "4")];
    assert!(task_from_env(env(&stepped), None).unwrap_err().contains("--array=0-3"));
    assert!(task_from_env(env(&slurm[..1]), None).unwrap_err().contains("SLURM_ARRAY_TASK_MIN"));
    let k8s = [("JOB_COMPLETION_INDEX", "3")];
    assert_eq!(task_from_env(env(&k8s), Some(8)), Ok((3, 8)));
    assert!(task_from_env(env(&k8s), None).unwrap_err().contains("--task-count"));
    let both = [("JOB_COMPLETION_INDEX", "3"), ("SLURM_ARRAY_TASK_ID", "1")];
    assert!(task_from_env(env(&both), Some(8)).unwrap_err().contains("both"));
    assert!(task_from_env(env(&[]), Some(8)).unwrap_err().contains("neither"));
    assert!(task_from_env(env(&[("JOB_COMPLETION_INDEX", "x")]), Some(8)).unwrap_err().contains("not a non-negative integer"));
}

#[test]
fn output_names_take_the_task_and_the_range() {
    let r = PassRange { start: 8, end: 16 };
    assert_eq!(expand_output(Path::new("parts/p-{task}.exr"), r, Some(2)).unwrap(), PathBuf::from("parts/p-2.exr"));
    assert_eq!(expand_output(Path::new("p-{passes}.exr"), r, None).unwrap(), PathBuf::from("p-8-16.exr"));
    assert!(expand_output(Path::new("p-{task}.exr"), r, None).is_err());
}

fn header(passes: PassRange) -> PartialHeader {
    PartialHeader {
        program: ember_host::program_version(),
        scene: "box".into(),
        scene_hash: 0xfeed,
        estimator: "pt".into(),
        config: "Pt".into(),
        seed: 3,
        width: 3,
        height: 2,
        passes,
        total: 10,
        tallies: Tallies::default(),
    }
}

fn part(path: &str, start: u32, end: u32) -> (PathBuf, PartialHeader) {
    (PathBuf::from(path), header(PassRange { start, end }))
}

/// Each refusal names its files and ranges. Injected bug checked: comparing only the
/// previous range's end with the next start (not the furthest end so far) missed
/// `0..10` overlapping `5..6` once `3..4` sat between them.
#[test]
fn merge_checks_name_mismatches_overlaps_and_gaps() {
    assert_eq!(check_parts(&[part("a", 0, 4), part("b", 4, 10)], Cover::All), Ok(PassRange { start: 0, end: 10 }));
    assert_eq!(check_parts(&[part("b", 4, 10), part("a", 0, 4)], Cover::All), Ok(PassRange { start: 0, end: 10 }), "any order");

    let gaps = check_parts(&[part("a", 0, 3), part("b", 5, 8)], Cover::All).unwrap_err().0;
    assert_eq!(gaps, vec!["passes 3..5 of 10 are missing".to_string(), "passes 8..10 of 10 are missing".to_string()]);

    let overlap = check_parts(&[part("a", 0, 6), part("b", 4, 10)], Cover::All).unwrap_err().0;
    assert_eq!(overlap, vec!["passes 4..10 of 'b' overlap passes 0..6 of 'a'".to_string()]);
    let nested = check_parts(&[part("a", 0, 10), part("b", 3, 4), part("c", 5, 6)], Cover::All).unwrap_err().0;
    assert_eq!(nested.len(), 2, "{nested:?}");
    assert!(nested[1].contains("5..6 of 'c' overlap passes 0..10 of 'a'"), "{nested:?}");
    let twice = check_parts(&[part("a", 0, 10), part("a-again", 0, 10)], Cover::All).unwrap_err().0;
    assert!(twice[0].contains("'a-again' overlap"), "{twice:?}");

    let mut other_seed = part("b", 4, 10);
    other_seed.1.seed = 4;
    let mut other_version = part("c", 4, 10);
    other_version.1.program = "ember 0.0.9 (commit 123)".into();
    let mut other_scene = part("d", 4, 10);
    other_scene.1.scene_hash = 0xbeef;
    let mismatch = check_parts(&[part("a", 0, 4), other_seed, other_version, other_scene], Cover::All).unwrap_err().0;
    assert_eq!(mismatch.len(), 3, "{mismatch:?}");
    assert!(mismatch[0].contains("'b' has seed 4, but 'a' has 3"), "{mismatch:?}");
    assert!(mismatch[1].contains("'c' has program version ember 0.0.9"), "{mismatch:?}");
    assert!(mismatch[2].contains("'d' has scene hash 000000000000beef"), "{mismatch:?}");
    assert!(check_parts(&[], Cover::All).is_err());
    // Staged merges: a contiguous run of parts covers its own range; a gap inside it is
    // still missing.
    assert_eq!(check_parts(&[part("c", 6, 8), part("b", 4, 6)], Cover::Contiguous), Ok(PassRange { start: 4, end: 8 }));
    let gap = check_parts(&[part("c", 7, 8), part("b", 4, 6)], Cover::Contiguous).unwrap_err().0;
    assert_eq!(gap, vec!["passes 6..7 of 10 are missing".to_string()]);
}

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("ember-distributed-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn film_with(passes: u32, value: f32) -> Film {
    let mut f = Film::new(3, 2);
    for p in 0..passes {
        let px: Vec<_> = (0..6).map(|i| ember_core::spectrum::Rgb::new(value * (i + 1) as f32, 1e-12 * p as f32, 1.0e12)).collect();
        f.set_camera_samples(ember_core::camera::CameraPass { seed: 0, pass: p }, 0..6, &px);
        f.end_pass(1.0);
    }
    f
}

/// The partial image keeps the exact sums (all 128 bits), the header and the tallies.
#[test]
fn partial_images_round_trip_exactly() {
    let path = temp("round-trip.exr");
    let film = film_with(4, 0.123_456_7);
    let h = header(PassRange { start: 2, end: 6 });
    write_partial(&path, &h, &film).unwrap();
    let (back, restored) = read_partial(&path).unwrap();
    assert_eq!(back, h);
    assert_eq!(read_partial_header(&path).unwrap(), h, "the header alone, as merge checks it");
    assert_eq!(restored.exact_sums(), film.exact_sums());
    assert_eq!(restored.passes(), 4);
    assert_eq!(restored.to_rgb_f32(), film.to_rgb_f32());
    // The top word is in use (1e12 × 4 passes ≈ 2^106 units).
    assert!(film.exact_sums()[0][2] >> 96 > 0);
}

/// Under a gaussian filter the partial image keeps the camera samples' weighted sums too
/// (issue 52), and the merged parts equal the whole film. Injected bug: `wsum` channels
/// not read back: the restored film's image lost its camera samples.
#[test]
fn partial_images_keep_a_wide_filters_weighted_sums() {
    let filter = ember_core::pixel_filter::Filter::Gaussian { stddev: 0.7 };
    let pass = |f: &mut Film, p: u32| {
        let px: Vec<_> = (0..6).map(|i| ember_core::spectrum::Rgb::new(0.3 * (i + p + 1) as f32, 2.0, 1.0e9)).collect();
        f.set_camera_samples(ember_core::camera::CameraPass { seed: 3, pass: p }, 0..6, &px);
        f.end_pass(1.0);
    };
    let mut whole = Film::with_filter(3, 2, filter);
    let mut first = Film::with_filter(3, 2, filter);
    let mut second = Film::with_filter(3, 2, filter);
    for p in 0..4 {
        pass(&mut whole, p);
        pass(if p < 2 { &mut first } else { &mut second }, p);
    }
    let path = temp("round-trip-gaussian.exr");
    write_partial(&path, &header(PassRange { start: 0, end: 2 }), &first).unwrap();
    let (_, mut restored) = read_partial(&path).unwrap();
    assert!(!restored.weighted_sums().is_empty());
    assert_eq!(restored.weighted_sums(), first.weighted_sums());
    assert_eq!(restored.to_rgb_f32(), first.to_rgb_f32());
    restored.merge(&second).unwrap();
    assert_eq!(restored.weighted_sums(), whole.weighted_sums());
    assert_eq!(restored.to_rgb_f32(), whole.to_rgb_f32());
}

/// Damaged, truncated and foreign files are refused with their name, never merged.
#[test]
fn damaged_or_foreign_files_are_refused() {
    let good = temp("good.exr");
    write_partial(&good, &header(PassRange { start: 0, end: 4 }), &film_with(4, 1.0)).unwrap();
    let bytes = std::fs::read(&good).unwrap();

    let truncated = temp("truncated.exr");
    std::fs::write(&truncated, &bytes[..bytes.len() * 2 / 3]).unwrap();
    let e = read_partial(&truncated).unwrap_err();
    assert!(e.contains("truncated.exr"), "{e}");

    let plain = temp("plain.exr");
    ember_formats::image_io::write_exr(&plain, 3, 2, &[[1.0; 3]; 6]).unwrap();
    let e = read_partial(&plain).unwrap_err();
    assert!(e.contains("plain.exr is not a partial image"), "{e}");

    // A header claiming more passes than its total.
    let lying = temp("lying.exr");
    let mut h = header(PassRange { start: 8, end: 12 });
    h.total = 10;
    write_partial(&lying, &h, &film_with(4, 1.0)).unwrap();
    let e = read_partial(&lying).unwrap_err();
    assert!(e.contains("reach past its total"), "{e}");

    let e = merge_parts(&[good.clone(), temp("missing.exr")], Cover::All).unwrap_err();
    assert!(e.contains("missing.exr"), "{e}");
}

/// An edited header is refused (issue 51: a part whose header claimed 0..8 for four
/// passes' sums merged into a half-bright image). Injected bugs checked: without the
/// checksum test in `header_from` the first edit reads as 8 passes; without the mean test
/// in `partial_from_image` the second file (checksum valid, passes wrong) does.
#[test]
fn edited_headers_are_refused() {
    let path = temp("edited.exr");
    write_partial(&path, &header(PassRange { start: 0, end: 4 }), &film_with(4, 1.0)).unwrap();
    let mut bytes = std::fs::read(&path).unwrap();
    let at = bytes.windows(12).position(|w| w == b"passes: 0..4").expect("the header is stored as text");
    bytes[at + 11] = b'8';
    std::fs::write(&path, &bytes).unwrap();
    for e in [read_partial(&path).unwrap_err(), read_partial_header(&path).unwrap_err()] {
        assert!(e.contains("edited.exr") && e.contains("checksum"), "{e}");
    }
    // A header written with the wrong pass count (its checksum valid): the stored mean
    // is not the sums' mean over the claimed passes.
    let wrong = temp("wrong-passes.exr");
    write_partial(&wrong, &header(PassRange { start: 0, end: 8 }), &film_with(4, 1.0)).unwrap();
    let e = read_partial(&wrong).unwrap_err();
    assert!(e.contains("wrong-passes.exr") && e.contains("not the mean of its sums over its 8 passes"), "{e}");
}

/// Two configuration dumps are reported by their first differing field, not in full
/// (a model trained with another --dataset printed two 600-character dumps).
#[test]
fn configuration_differences_name_the_field() {
    let a = "Spcbpt(SpcbptConfig { light_paths: None, dataset: Some(1000), subspaces: None }); max depth -1, heuristic Power";
    let b = "Spcbpt(SpcbptConfig { light_paths: None, dataset: Some(2000), subspaces: None }); max depth -1, heuristic Power";
    let pair = |a: &str, b: &str| (a.to_string(), b.to_string());
    assert_eq!(first_difference(a, b), pair("dataset Some(1000)", "dataset Some(2000)"));
    assert_eq!(first_difference("Pt; max depth 5", "Pt; max depth 7"), pair("max depth 5", "max depth 7"));
}
