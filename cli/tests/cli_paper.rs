//! `eigenmpc paper --quick`: every figure (PNG and SVG) and every claim's
//! verdict line of `report.md` are written; an unwritable folder is refused
//! before any run. (The full run's verdicts are checked against
//! `docs/paper/report.md` by `tests/python/test_paper.py`, release build.)

mod common;
use common::{eigenmpc, eigenmpc_ok};

const FIGURES: [&str; 7] = [
    "fig1-surface",
    "fig2-alpha",
    "fig3-modes",
    "fig4-straight",
    "fig5-curved",
    "fig6-large-ic",
    "fig7-hybrid",
];

#[test]
fn quick_run_writes_every_figure_and_verdict() {
    let dir = std::env::temp_dir().join(format!("eigenmpc-paper-{}", std::process::id()));
    let stdout = eigenmpc_ok(&["paper", "--quick", "--out", dir.to_str().unwrap()]);
    for stem in FIGURES {
        let png = std::fs::read(dir.join(format!("{stem}.png"))).expect(stem);
        assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n", "{stem}.png is a PNG");
        assert!(
            png.len() > 20_000,
            "{stem}.png has content ({} bytes)",
            png.len()
        );
        let svg = std::fs::read_to_string(dir.join(format!("{stem}.svg"))).expect(stem);
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
    }
    let report = std::fs::read_to_string(dir.join("report.md")).unwrap();
    assert!(report.contains("Reduced run (`--quick`)"));
    for i in 1..=22 {
        let line = report
            .lines()
            .find(|l| l.starts_with(&format!("| C{i} |")))
            .unwrap_or_else(|| panic!("claim C{i} has no line in report.md"));
        assert!(
            ["**holds**:", "**partly**:", "**differs**:"]
                .iter()
                .any(|v| line.contains(v)),
            "C{i} has no verdict: {line}"
        );
        assert!(stdout.contains(&format!("C{i} ")), "C{i} printed");
    }
    for stem in FIGURES {
        assert!(report.contains(&format!("]({stem}.png)")), "{stem} linked");
    }
    // 17 runs, each in the per-run table.
    assert_eq!(
        report
            .lines()
            .filter(|l| l.starts_with("| fig")
                || l.starts_with("| hybrid")
                || l.starts_with("| curved")
                || l.starts_with("| anti"))
            .count(),
        17
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn an_unwritable_folder_is_refused_before_the_runs() {
    let file = std::env::temp_dir().join(format!("eigenmpc-paper-file-{}", std::process::id()));
    std::fs::write(&file, b"not a folder").unwrap();
    let out = eigenmpc(&["paper", "--quick", "--out", file.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.starts_with("error: creating"), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    std::fs::remove_file(&file).ok();
}
