//! One schema for `summary.json` (issue #30): `demo`, `task` and `online` start their summaries
//! with the same facts (command, subject, pipeline, seed, paradigm, calibration), and `demo`
//! and `online` write the same result and decision rows, and the same files; all three the bits
//! delivered in the first minutes.

mod common;

fn summary(dir: &std::path::Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

#[test]
fn demo_task_and_online_write_one_summary_schema() {
    let dir = common::tmp_dir("summary-schema");
    let quick = [
        "--paradigm",
        "fast",
        "--calibration-per-bulb",
        "3",
        "--seed",
        "4",
    ];
    let run = |name: &str, args: &[&str]| {
        let out = dir.join(name);
        let mut all: Vec<&str> = args.to_vec();
        all.extend(quick);
        all.extend(["--out", out.to_str().unwrap()]);
        let (ok, stdout, err) = common::oddball(&all);
        assert!(ok, "{name}: {err}\n{stdout}");
        summary(&out)
    };
    let demo = run("demo", &["demo", "--commands", "up,left"]);
    let task = run("task", &["task", "draw", "--draw", "L"]);
    let online = run(
        "online",
        &["online", "--calibrate", "--fast", "--commands", "up,left"],
    );
    for (what, s) in [("demo", &demo), ("task", &task), ("online", &online)] {
        assert_eq!(s["command"], what, "{s}");
        assert_eq!(s["subject"], "typical", "{what}: {s}");
        assert_eq!(s["pipeline"], "lda", "{what}");
        assert_eq!(s["seed"], 4, "{what}");
        assert_eq!(s["paradigm"], demo["paradigm"], "{what}: same timing");
        assert_eq!(s["calibration"]["trials"], 12, "{what}: {s}");
        for key in ["epochs", "targets", "rejected", "cv_auc", "d_prime"] {
            assert!(s["calibration"][key].is_number(), "{what}: {key} in {s}");
        }
    }
    assert_eq!(task["task"], "draw");
    // Each says what it delivered in its first 5 and 10 minutes, its calibration's time
    // counted: every decision here falls inside both (the sessions last about a minute).
    for (what, s) in [("demo", &demo), ("task", &task), ("online", &online)] {
        let n = match what {
            "task" => task["report"]["steps"].as_array().unwrap().len(),
            _ => 2,
        };
        let h = s["bits_since_start"]
            .as_array()
            .unwrap_or_else(|| panic!("{what}: {s}"));
        assert_eq!(h.len(), 2, "{what}: {s}");
        for (b, minutes) in h.iter().zip([5.0, 10.0]) {
            assert_eq!(b["minutes"], minutes, "{what}");
            let made = b["made"].as_u64().unwrap() as usize;
            assert_eq!(
                made + b["abstained"].as_u64().unwrap() as usize,
                n,
                "{what}: {b}"
            );
            assert_eq!(b["session_shorter"], true, "{what}: {b}");
            assert!(
                b["bits"].as_f64().unwrap() <= 2.0 * made as f64 + 1e-9,
                "{what}: {b}"
            );
        }
    }
    // online writes the pictures demo writes.
    for file in ["decisions.csv", "pen_trace.png", "erp.png", "model.json"] {
        for what in ["demo", "online"] {
            assert!(dir.join(what).join(file).is_file(), "{what}: {file}");
        }
    }
    // Live sessions count what went wrong with what the person was shown.
    for (what, s) in [("task", &task), ("online", &online)] {
        assert!(s["presentation"].is_object(), "{what}: {s}");
        assert_eq!(s["presentation"]["undrawn_flashes"], 0, "{what}: {s}");
    }
    for (what, s) in [("demo", &demo), ("online", &online)] {
        assert_eq!(s["result"]["decisions"], 2, "{what}: {s}");
        let keys = |r: &serde_json::Value| {
            let mut k: Vec<String> = r.as_object().unwrap().keys().cloned().collect();
            k.sort();
            k
        };
        assert_eq!(keys(&s["result"]), keys(&demo["result"]), "{what}");
        let rows = s["decisions"].as_array().unwrap();
        assert_eq!(rows.len(), 2, "{what}");
        assert_eq!(keys(&rows[0]), keys(&demo["decisions"][0]), "{what}");
        assert_eq!(rows[0]["index"], 1);
        assert_eq!(rows[0]["intended"], demo["decisions"][0]["intended"]);
    }
}
