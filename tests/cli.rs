//! End-to-end checks of the `neumann` command: exit codes, messages, files written, Ctrl-C.

use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::time::Duration;

fn neumann() -> Command {
    Command::new(env!("CARGO_BIN_EXE_neumann"))
}

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("neumann-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

#[test]
fn renders_the_builtin_scene_to_each_format() {
    for ext in ["png", "exr", "pfm"] {
        let out = temp(&format!("cbox.{ext}"));
        let r = neumann().args(["render", "--res", "12x8", "--spp", "2", "--quiet", "-o"]).arg(&out).output().unwrap();
        let stdout = String::from_utf8_lossy(&r.stdout);
        assert!(r.status.success(), "{ext}: {stdout} {}", String::from_utf8_lossy(&r.stderr));
        assert!(stdout.contains("wrote") && stdout.contains("2 spp"), "{stdout}");
        assert!(std::fs::metadata(&out).unwrap().len() > 0);
    }
    let (w, h, px) = neumann::film::output::read_pfm(&temp("cbox.pfm")).unwrap();
    assert_eq!((w, h), (12, 8));
    assert!(px.iter().any(|c| c.x > 0.0), "image is black");
}

#[test]
fn bad_arguments_exit_2_with_a_message() {
    for args in [
        vec!["render", "--res", "0"],
        vec!["render", "--res", "12xq"],
        vec!["render", "--spp", "0"],
        vec!["render", "--spp", "many"],
        vec!["render", "--max-depth", "-7"],
        vec!["render", "-D", "colour=blue"],
        vec!["render", "-D", "spp"],
        vec!["render", "--time", "-1"],
        vec!["render", "--time", "1e300"],
        vec!["render", "--res", "100000x100000"],
        vec!["render", "--exposure", "NaN"],
        vec!["render", "-o", "image.jpg"],
        vec!["render", "--sampler", "halton"],
        vec!["render", "--light-sampler", "bhv"],
        vec!["render", "--light-sampler", "power", "--integrator", "ptracer"],
        vec!["frobnicate"],
    ] {
        let r = neumann().args(&args).output().unwrap();
        let err = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains("error"), "{args:?}: no message in {err}");
    }
    let r = neumann().args(["render", "nosuchscene"]).output().unwrap();
    assert_eq!(r.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&r.stderr).contains("cbox"));
}

#[test]
fn defines_override_scene_defaults() {
    let out = temp("small.pfm");
    let r = neumann().args(["render", "-Dres=6x4", "-Dspp=3", "--quiet", "-o"]).arg(&out).output().unwrap();
    assert!(r.status.success());
    assert!(String::from_utf8_lossy(&r.stdout).contains("6x4, 3 spp"));
}

/// SIGINT and SIGTERM both finish the samples in flight, write the image (replacing an earlier
/// file only once the new one is complete, through a temporary file that does not stay) and exit
/// with 128 + the signal (130, 143), so scripts know the image is partial.
#[test]
fn interrupt_writes_what_was_rendered() {
    for (signal, code) in [("-INT", 130), ("-TERM", 143)] {
        let out = temp(&format!("interrupted{code}.exr"));
        std::fs::write(&out, b"an earlier image").unwrap();
        let child = neumann()
            .args(["render", "--res", "64", "--spp", "1000000", "--quiet", "-o"])
            .arg(&out)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        std::thread::sleep(Duration::from_millis(1500));
        let killed = Command::new("kill").args([signal, &child.id().to_string()]).status().unwrap();
        assert!(killed.success());
        let r = child.wait_with_output().unwrap();
        let stdout = String::from_utf8_lossy(&r.stdout);
        let stderr = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(code), "{stdout} {stderr}");
        assert!(stdout.contains("interrupted") && stderr.contains("stopped by signal"), "{stdout} {stderr}");
        let img = neumann::load::image::load_image(&out, false).unwrap();
        assert_eq!((img.width, img.height), (64, 64));
        let leftovers: Vec<_> = std::fs::read_dir(out.parent().unwrap())
            .unwrap()
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().contains(".tmp-"))
            .collect();
        assert!(leftovers.is_empty(), "temporary files left: {leftovers:?}");
    }
}

/// The destination is checked before rendering: a missing folder is an error at once (exit 1),
/// not after the render; more than 1024 threads is a usage error.
#[test]
fn the_destination_is_checked_first() {
    let start = std::time::Instant::now();
    let r = neumann().args(["render", "--spp", "100000", "-o", "/nonexistent-folder/x.png"]).output().unwrap();
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("does not exist") && start.elapsed() < Duration::from_secs(5), "{stderr}");
    let r = neumann().args(["render", "--threads", "100000", "-o"]).arg(temp("t.png")).output().unwrap();
    assert_eq!(r.status.code(), Some(2));
    // The film's memory is checked against the budget before rendering.
    let r = neumann().args(["render", "--res", "16384x4096", "--max-memory", "1G", "-o"]).arg(temp("m.png")).output().unwrap();
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("GiB") && stderr.contains("--max-memory"), "{stderr}");
}

/// A Mitsuba XML scene renders with -D overrides; a broken one fails with exit code 1 and a
/// `file:line:col` message quoting the line; unused parameters are warned about.
#[test]
fn scene_files_render_and_bad_ones_fail_with_their_position() {
    let scene = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/cbox.xml");
    let out = temp("xml.png");
    let r =
        neumann().arg("render").arg(&scene).args(["-Dres=10", "-Dspp=2", "--quiet", "-o"]).arg(&out).output().unwrap();
    let stdout = String::from_utf8_lossy(&r.stdout);
    assert!(r.status.success(), "{stdout} {}", String::from_utf8_lossy(&r.stderr));
    assert!(stdout.contains("at 10x10") && stdout.contains("2 spp"), "{stdout}");

    let bad = temp("bad.xml");
    std::fs::write(
        &bad,
        "<scene version=\"3.0.0\">\n  <sensor type=\"perspective\"/>\n  <shape type=\"sphere\">\n    <bsdf type=\"difuse\"/>\n  </shape>\n</scene>\n",
    )
    .unwrap();
    let r = neumann().arg("render").arg(&bad).output().unwrap();
    let err = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(1), "{err}");
    assert!(err.contains("bad.xml:4:5:") && err.contains("'diffuse'") && err.contains("4 |     <bsdf"), "{err}");

    let warn = temp("warn.xml");
    std::fs::write(
        &warn,
        "<scene version=\"3.0.0\">\n  <sensor type=\"perspective\">\n    <film type=\"hdrfilm\"><integer name=\"width\" value=\"4\"/><integer name=\"height\" value=\"4\"/></film>\n  </sensor>\n  <shape type=\"sphere\"><float name=\"raidus\" value=\"2\"/></shape>\n</scene>\n",
    )
    .unwrap();
    let r = neumann().arg("render").arg(&warn).args(["--quiet", "-o"]).arg(temp("warn.png")).output().unwrap();
    let err = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(1), "a parameter no plugin reads is an error, as in Mitsuba 3: {err}");
    assert!(err.contains("warn.xml:5:") && err.contains("does not take the parameter float 'raidus'"), "{err}");
}

/// `--bounces-out` writes one image per Neumann-series term, their sum and a contact sheet.
#[test]
fn bounces_out_writes_the_terms() {
    let dir = temp("terms");
    let r = neumann()
        .args(["render", "--res", "8", "--spp", "2", "--max-depth", "3", "--quiet", "-o"])
        .arg(temp("terms.png"))
        .arg("--bounces-out")
        .arg(&dir)
        .output()
        .unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    for f in ["term0.exr", "term1.exr", "term2.exr", "sum.exr", "terms.png"] {
        assert!(dir.join(f).exists(), "{f} missing");
    }
    assert!(!dir.join("term3.exr").exists(), "max_depth 3 has three terms");
}

/// `converge` measures each strategy, fits slopes and writes the CSV and both plots.
#[test]
fn converge_writes_csv_and_plots() {
    let dir = temp("converge");
    let r = neumann()
        .args(["converge", "--res", "8", "--max-spp", "4", "--max-depth", "2", "--direct", "mis,bsdf", "--out"])
        .arg(&dir)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&r.stdout);
    assert!(r.status.success(), "{stdout} {}", String::from_utf8_lossy(&r.stderr));
    assert!(stdout.contains("no --ref") && stdout.contains("bsdf"), "{stdout}");
    for f in ["convergence.csv", "convergence.svg", "convergence.png", "reference.exr"] {
        assert!(dir.join(f).exists(), "{f} missing");
    }
    let csv = std::fs::read_to_string(dir.join("convergence.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + 2 * 3, "{csv}");
}

#[test]
fn the_three_solvers_run_from_the_command_line() {
    let csv = temp("patches.csv");
    for (integrator, extra) in
        [("ptracer", vec![]), ("radiosity", vec!["--patch-size", "0.5", "--smooth", "--patches-out"])]
    {
        let out = temp(&format!("{integrator}.pfm"));
        let mut cmd = neumann();
        cmd.args(["render", "--res", "16x12", "--spp", "4", "--quiet", "--integrator", integrator]).args(&extra);
        if integrator == "radiosity" {
            cmd.arg(&csv);
        }
        let r = cmd.arg("-o").arg(&out).output().unwrap();
        let stdout = String::from_utf8_lossy(&r.stdout);
        assert!(r.status.success(), "{integrator}: {stdout} {}", String::from_utf8_lossy(&r.stderr));
        let (w, h, px) = neumann::film::output::read_pfm(&out).unwrap();
        assert_eq!((w, h), (16, 12));
        assert!(px.iter().any(|c| c.x > 0.0) && px.iter().all(|c| c.is_finite()), "{integrator}: image");
        if integrator == "radiosity" {
            assert!(stdout.contains("patches") && stdout.contains("residual"), "{stdout}");
        }
    }
    let table = std::fs::read_to_string(&csv).unwrap();
    assert!(table.starts_with("patch,shape,area") && table.lines().count() > 100, "{}", &table[..200.min(table.len())]);
    // Radiosity flags without radiosity, and a bad patch size: usage errors.
    for args in [vec!["render", "--smooth"], vec!["render", "--integrator", "radiosity", "--patch-size", "0"]] {
        let r = neumann().args(&args).output().unwrap();
        assert_eq!(r.status.code(), Some(2), "{args:?}");
        assert!(
            String::from_utf8_lossy(&r.stderr).contains("radiosity")
                || String::from_utf8_lossy(&r.stderr).contains("patch")
        );
    }
    // Radiosity refuses non-diffuse scenes with a clear error.
    let scene = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/caustics.xml");
    let r = neumann()
        .args(["render", "--res", "8", "--spp", "1", "--quiet", "--integrator", "radiosity"])
        .arg(&scene)
        .arg("-o")
        .arg(temp("x.png"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(1), "{err}");
    assert!(err.contains("radiosity"), "{err}");
}

/// `--light-sampler` renders with each sampler; the images differ only by noise (same mean
/// within a few percent at 16 spp on the built-in Cornell box, one light).
#[test]
fn light_sampler_flag() {
    let mut means = Vec::new();
    for kind in ["bvh", "power", "uniform"] {
        let out = temp(&format!("ls-{kind}.pfm"));
        let r = neumann()
            .args(["render", "--res", "24", "--spp", "16", "--quiet", "--light-sampler", kind, "-o"])
            .arg(&out)
            .output()
            .unwrap();
        assert!(r.status.success(), "{kind}: {}", String::from_utf8_lossy(&r.stderr));
        let (_, _, px) = neumann::film::output::read_pfm(&out).unwrap();
        means.push(px.iter().map(|c| (c.x + c.y + c.z) as f64).sum::<f64>() / px.len() as f64);
    }
    for m in &means {
        assert!((m / means[0] - 1.0).abs() < 0.05, "{means:?}");
    }
}

/// A closed standard output (`neumann render | head -1`) is no reason to panic: the render
/// finishes and writes its image.
#[test]
fn a_closed_stdout_does_not_stop_the_render() {
    let out = temp("closed-stdout.png");
    let mut child = neumann()
        .args(["render", "--res", "16", "--spp", "4", "-o"])
        .arg(&out)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take()); // the reader goes away before anything is printed
    let r = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert!(r.status.success(), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(std::fs::metadata(&out).unwrap().len() > 0);
}

/// `--integrator moment` writes Mitsuba's moment layers beside R, G, B in the EXR (and a PNG
/// output says it leaves them out).
#[test]
fn moment_layers_go_to_the_exr() {
    let out = temp("moment.exr");
    let r = neumann().args(["render", "--res", "8", "--spp", "4", "--integrator", "moment", "-o"]).arg(&out).output().unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let image = exr::prelude::read_all_flat_layers_from_file(&out).unwrap();
    let names: Vec<String> = image.layer_data[0].channel_data.list.iter().map(|c| c.name.to_string()).collect();
    for n in ["R", "G", "B", "_arg_0.X", "_arg_0.Y", "_arg_0.Z", "m2__arg_0.X", "m2__arg_0.Y", "m2__arg_0.Z"] {
        assert!(names.iter().any(|c| c == n), "{n} missing from {names:?}");
    }
    let png = temp("moment.png");
    let r = neumann().args(["render", "--res", "8", "--spp", "4", "--integrator", "moment", "-o"]).arg(&png).output().unwrap();
    assert!(r.status.success());
    assert!(String::from_utf8_lossy(&r.stdout).contains("are not written: only .exr holds them"));
}

/// Mitsuba's integrator `timeout` stops the render there (in whole passes) when the sample
/// count would take longer; `--time` overrides it.
#[test]
fn the_scene_timeout_limits_the_render() {
    let scene = temp("timeout.xml");
    std::fs::write(
        &scene,
        r#"<scene version="3.0.0">
    <integrator type="path"><float name="timeout" value="0.3"/></integrator>
    <sensor type="perspective"><sampler type="independent"><integer name="sample_count" value="1000000"/></sampler>
        <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="32"/></film></sensor>
    <emitter type="constant"/><shape type="sphere"/>
</scene>"#,
    )
    .unwrap();
    let out = temp("timeout.exr");
    let start = std::time::Instant::now();
    let r = neumann().args(["render", "--quiet", "-o"]).arg(&out).arg(&scene).output().unwrap();
    let stdout = String::from_utf8_lossy(&r.stdout);
    assert!(r.status.success(), "{stdout} {}", String::from_utf8_lossy(&r.stderr));
    assert!(start.elapsed() < Duration::from_secs(20), "the timeout stops the render");
    assert!(stdout.contains("wrote") && !stdout.contains("(1000000 spp"), "{stdout}");
}

/// On a scene file, flags are parameters of its objects: a bad one is a usage error (exit 2)
/// located at the flag, in the plugin's words.
#[test]
fn flags_on_scene_files_are_validated_by_the_plugins() {
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/cbox.xml");
    let r = neumann()
        .args(["render", scene, "--integrator", "radiosity", "--max-depth", "3", "-o"])
        .arg(temp("r.png"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(2), "{err}");
    assert!(err.contains("command line:1:1:") && err.contains("--max-depth 3") && err.contains("max_depth"), "{err}");
    let r = neumann().args(["render", scene, "--res", "16x8", "--spp", "2", "--quiet", "-o"]).arg(temp("f.pfm")).output().unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let (w, h, _) = neumann::film::output::read_pfm(&temp("f.pfm")).unwrap();
    assert_eq!((w, h), (16, 8));
}

/// `--checkpoint` saves the render's state; `--resume` continues it to more samples with the
/// same image as a render that never stopped (bit-identical pixels), and refuses a state of
/// other settings or one that already holds the samples asked for.
#[test]
fn checkpoint_and_resume() {
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/cbox.xml");
    let (part, resumed, whole) = (temp("part.pfm"), temp("resumed.pfm"), temp("whole.pfm"));
    let run = |args: &[&str], out: &std::path::Path| {
        let r = neumann().args(["render", scene, "--res", "24x16", "--quiet"]).args(args).arg("-o").arg(out).output().unwrap();
        (r.status.code(), String::from_utf8_lossy(&r.stderr).to_string())
    };
    assert_eq!(run(&["--spp", "8", "--checkpoint", "0.001"], &part).0, Some(0));
    let state = format!("{}.state", part.display());
    assert_eq!(run(&["--spp", "24", "--resume", &state], &resumed).0, Some(0));
    assert_eq!(run(&["--spp", "24"], &whole).0, Some(0));
    let (_, _, a) = neumann::film::output::read_pfm(&resumed).unwrap();
    let (_, _, b) = neumann::film::output::read_pfm(&whole).unwrap();
    assert!(a == b, "the resumed render differs from the uninterrupted one");
    let (code, err) = run(&["--spp", "24", "--seed", "5", "--resume", &state], &resumed);
    assert!(code == Some(1) && err.contains("other settings"), "{err}");
    let (code, err) = run(&["--spp", "8", "--resume", &state], &resumed);
    assert!(code == Some(2) && err.contains("already holds 8 spp"), "{err}");
}

/// `render --part` and `--pixel-bounds` write parts that `merge` combines into the single
/// render's image (within float rounding); bad splits are usage errors, missing parts are named.
#[test]
fn split_render_and_merge() {
    let whole = temp("split-whole.exr");
    let base = ["render", "--res", "20x12", "--spp", "12", "--seed", "5", "--quiet"];
    let run = |extra: &[&str], out: &PathBuf| {
        let r = neumann().args(base).args(extra).arg("-o").arg(out).output().unwrap();
        assert!(r.status.success(), "{extra:?}: {}", String::from_utf8_lossy(&r.stderr));
        String::from_utf8_lossy(&r.stdout).to_string()
    };
    run(&[], &whole);
    let parts = [temp("split-1.exr"), temp("split-2a.exr"), temp("split-2b.exr")];
    let said = run(&["--part", "1/2"], &parts[0]);
    assert!(said.contains("part 1/2: samples 0–6 of 12") && said.contains("neumann merge"), "{said}");
    run(&["--part", "2/2", "--pixel-bounds", "0,20,0,5"], &parts[1]);
    run(&["--part", "2/2", "--pixel-bounds", "0,20,5,12"], &parts[2]);
    let merged = temp("split-merged.exr");
    let r = neumann().arg("merge").args(&parts).arg("-o").arg(&merged).output().unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let rgb = |p: &PathBuf| -> Vec<f32> {
        let image = exr::prelude::read_all_flat_layers_from_file(p).unwrap();
        let layer = &image.layer_data[0];
        ["R", "G", "B"]
            .iter()
            .flat_map(|n| layer.channel_data.list.iter().find(|c| c.name.eq(n)).unwrap().sample_data.values_as_f32().collect::<Vec<_>>())
            .collect()
    };
    let (m, w) = (rgb(&merged), rgb(&whole));
    assert!(m.iter().zip(&w).all(|(a, b)| (a - b).abs() <= b.abs() * 1e-6), "merged differs from the single render");
    // A missing part is named; --allow-partial merges the rest.
    let r = neumann().arg("merge").args(&parts[..2]).arg("-o").arg(temp("split-partial.png")).output().unwrap();
    let err = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(1), "{err}");
    assert!(err.contains("missing: samples 6–12 of pixels x 0–20, y 5–12 (part 2/2)"), "{err}");
    let r = neumann().arg("merge").args(&parts[..2]).arg("--allow-partial").arg("-o").arg(temp("split-partial.png")).output().unwrap();
    assert!(r.status.success() && String::from_utf8_lossy(&r.stdout).contains("partial"));
    for (extra, says) in [
        (vec!["--part", "0/3"], "--part expects I/N"),
        (vec!["--part", "3"], "--part expects I/N"),
        (vec!["--part", "13/13"], "do not split into 13 parts"),
        (vec!["--pixel-bounds", "0,30,0,4"], "reach outside the image"),
        (vec!["--pixel-bounds", "5,5,0,4"], "X0 < X1"),
        (vec!["--part", "1/2", "-o", "part.png"], "name the output .exr"),
    ] {
        let r = neumann().args(base).args(&extra).output().unwrap();
        let err = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{extra:?}: {err}");
        assert!(err.contains(says), "{extra:?}: {err}");
    }
    let r = neumann().args(["merge", "no-such-part.exr", "-o"]).arg(temp("x.exr")).output().unwrap();
    assert_eq!(r.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&r.stderr).contains("no-such-part.exr"));
}

/// The README's excerpt of `neumann mc` is what the command prints (the demo is deterministic).
#[test]
fn the_readme_quotes_mc_as_it_prints() {
    let readme = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/README.md")).unwrap();
    let start = readme.find("estimator                           N     estimate").expect("the mc excerpt");
    let excerpt = &readme[start..start + readme[start..].find("```").unwrap()];
    let r = neumann().arg("mc").output().unwrap();
    assert!(r.status.success());
    let out = String::from_utf8_lossy(&r.stdout);
    for line in excerpt.lines().filter(|l| !l.trim().is_empty()) {
        assert!(out.lines().any(|l| l == line), "the README quotes a line mc does not print:\n{line}");
    }
}

/// `--aov` writes the listed AOVs and the variance (with the sample count) as EXR layers, and
/// refuses what it cannot do.
#[test]
fn aov_flag_writes_layers() {
    let out = temp("aov.exr");
    let r = neumann().args(["render", "--res", "16", "--spp", "8", "--quiet", "--aov", "albedo,normal,depth,position,variance", "-o"]).arg(&out).output().unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let image = exr::prelude::read_all_flat_layers_from_file(&out).unwrap();
    let names: Vec<String> = image.layer_data[0].channel_data.list.iter().map(|c| c.name.to_string()).collect();
    for n in ["R", "albedo.R", "normal.Z", "depth.T", "position.X", "variance.G", "spp"] {
        assert!(names.iter().any(|m| m == n), "{n} missing from {names:?}");
    }
    let get = |n: &str| -> Vec<f32> {
        let c = image.layer_data[0].channel_data.list.iter().find(|c| c.name.eq(n)).unwrap();
        c.sample_data.values_as_f32().collect()
    };
    assert!(get("spp").iter().all(|&s| s == 8.0));
    let depth = get("depth.T");
    assert!(depth.iter().filter(|&&d| d > 0.0).count() > depth.len() * 3 / 4, "the box fills most of the frame");
    assert!(get("variance.G").iter().all(|&v| v >= 0.0) && get("variance.G").iter().any(|&v| v > 0.0));
    for (flags, says) in [
        (vec!["--aov", "shininess"], "unknown AOV 'shininess'"),
        (vec!["--aov", "albedo", "-o", "x.png"], "name the output .exr"),
        (vec!["--aov", "albedo", "--integrator", "ptracer", "-o", "x.exr"], "traces none"),
    ] {
        let r = neumann().args(["render", "--res", "8", "--spp", "1"]).args(&flags).output().unwrap();
        let err = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{flags:?}: {err}");
        assert!(err.contains(says), "{flags:?}: {err}");
    }
}

/// `--display` sends the render to tev: a fake tev on loopback gets the image's creation and
/// updates whose last one is the written image; an unreachable tev is a warning, not a failure.
#[test]
fn display_sends_the_render_to_tev() {
    use neumann::film::tev::fake::{serve, Packet};
    let (address, server) = serve().unwrap();
    let out = temp("display.exr");
    let r = neumann().args(["render", "--res", "20x10", "--spp", "4", "--quiet", "--display", &address, "-o"]).arg(&out).output().unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let packets = server.join().unwrap().unwrap();
    let channels: Vec<String> = ["R", "G", "B"].map(String::from).to_vec();
    assert_eq!(packets[0], Packet::Create { name: "cbox".into(), size: [20, 10], channels: channels.clone() });
    let Some(Packet::Update { tile, values, channels: c, .. }) = packets.last() else { panic!("no update: {packets:?}") };
    assert_eq!((tile, c), (&[0, 0, 20, 10], &channels));
    let image = exr::prelude::read_all_flat_layers_from_file(&out).unwrap();
    let red: Vec<f32> = image.layer_data[0].channel_data.list.iter().find(|c| c.name.eq("R")).unwrap().sample_data.values_as_f32().collect();
    assert_eq!(values[0], red, "the last update is the final image");
    let r = neumann().args(["render", "--res", "8", "--spp", "1", "--quiet", "--display", "127.0.0.1:1", "-o"]).arg(temp("nodisplay.exr")).output().unwrap();
    assert!(r.status.success());
    assert!(String::from_utf8_lossy(&r.stderr).contains("cannot connect to tev at 127.0.0.1:1"));
}

/// Without the `oidn` feature, `--denoise` says how to get it (exit 2).
#[cfg(not(feature = "oidn"))]
#[test]
fn denoise_without_the_feature_says_how_to_enable_it() {
    let r = neumann().args(["render", "--res", "8", "--spp", "1", "--denoise", "-o"]).arg(temp("d.png")).output().unwrap();
    let err = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(2), "{err}");
    assert!(err.contains("built without denoising") && err.contains("--features oidn") && err.contains("pyoidn"), "{err}");
}

/// With the `oidn` feature, `--denoise` writes the denoised image with the noisy one as a layer
/// of an EXR, or beside a PNG; the denoised image is smoother than the noisy one.
#[cfg(feature = "oidn")]
#[test]
fn denoise_writes_the_denoised_image_and_keeps_the_noisy_one() {
    let out = temp("denoised.exr");
    let r = neumann().args(["render", "--res", "32", "--spp", "4", "--quiet", "--denoise", "-o"]).arg(&out).output().unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    assert!(String::from_utf8_lossy(&r.stdout).contains("denoised with Open Image Denoise"));
    let image = exr::prelude::read_all_flat_layers_from_file(&out).unwrap();
    let get = |n: &str| -> Vec<f32> {
        let c = image.layer_data[0].channel_data.list.iter().find(|c| c.name.eq(n)).unwrap_or_else(|| panic!("no {n}"));
        c.sample_data.values_as_f32().collect()
    };
    let roughness = |v: &[f32]| v.windows(2).map(|w| (w[1] - w[0]).abs().min(1.0)).sum::<f32>();
    let (clean, noisy) = (get("G"), get("noisy.G"));
    assert!(roughness(&clean) < roughness(&noisy) / 2.0, "{} vs {}", roughness(&clean), roughness(&noisy));
    let png = temp("denoised.png");
    let r = neumann().args(["render", "--res", "16", "--spp", "2", "--quiet", "--denoise", "-o"]).arg(&png).output().unwrap();
    assert!(r.status.success());
    assert!(temp("denoised.noisy.png").exists(), "the noisy image beside the PNG");
}

/// `--noise-threshold`: an adaptive render reports its mean samples per pixel and writes the
/// per-pixel counts; bad values and misplaced companions are usage errors.
#[test]
fn noise_threshold_renders_adaptively() {
    let out = temp("adaptive.exr");
    let r = neumann().args(["render", "--res", "24", "--spp", "64", "--quiet", "--noise-threshold", "0.05", "-o"]).arg(&out).output().unwrap();
    let said = String::from_utf8_lossy(&r.stdout);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    assert!(said.contains("adaptive sampling (noise threshold 0.05): mean"), "{said}");
    let image = exr::prelude::read_all_flat_layers_from_file(&out).unwrap();
    let spp: Vec<f32> = image.layer_data[0].channel_data.list.iter().find(|c| c.name.eq("spp")).unwrap().sample_data.values_as_f32().collect();
    assert!(spp.iter().any(|&c| c < 64.0) && spp.iter().all(|&c| (16.0..=64.0).contains(&c)), "{spp:?}");
    for (flags, says) in [
        (vec!["--noise-threshold", "0"], "positive number"),
        (vec!["--min-spp", "8"], "give --noise-threshold too"),
        (vec!["--noise-threshold", "0.1", "--integrator", "ptracer"], "has none"),
        (vec!["--noise-threshold", "0.1", "--part", "1/2", "-o", "p.exr"], "not with --part"),
    ] {
        let r = neumann().args(["render", "--res", "8", "--spp", "4"]).args(&flags).output().unwrap();
        let err = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{flags:?}: {err}");
        assert!(err.contains(says), "{flags:?}: {err}");
    }
}

/// glTF files render like Mitsuba scenes; `--camera` chooses among their cameras; the flags
/// that do not apply to a format are usage errors.
#[test]
fn gltf_scenes_render_and_choose_their_camera() {
    let scene = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/gltf_demo.gltf");
    let out = temp("gltf.png");
    let r = neumann().arg("render").arg(&scene).args(["--res", "24x16", "--spp", "2", "--camera", "view", "--quiet", "-o"]).arg(&out).output().unwrap();
    let stdout = String::from_utf8_lossy(&r.stdout);
    assert!(r.status.success(), "{stdout} {}", String::from_utf8_lossy(&r.stderr));
    assert!(stdout.contains("at 24x16") && stdout.contains("2 spp"), "{stdout}");
    for (args, needle) in [
        (vec!["--camera", "nope"], "--camera nope"),
        (vec!["-Dres=4"], "-D res"),
    ] {
        let r = neumann().arg("render").arg(&scene).args(&args).args(["--quiet", "-o"]).arg(&out).output().unwrap();
        let err = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(needle), "{err}");
    }
    let xml = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/cbox.xml");
    let r = neumann().arg("render").arg(&xml).args(["--camera", "0", "--quiet", "-o"]).arg(&out).output().unwrap();
    assert_eq!(r.status.code(), Some(2), "{}", String::from_utf8_lossy(&r.stderr));
    let r = neumann().args(["render", "--camera", "0", "--quiet", "-o"]).arg(&out).output().unwrap();
    assert_eq!(r.status.code(), Some(2), "the built-in scene has one camera: {}", String::from_utf8_lossy(&r.stderr));
}

/// pbrt-v4 files render from the command line.
#[test]
fn pbrt_scenes_render() {
    let out = temp("pbrt.png");
    for name in ["pbrt_demo", "pbrt_procedural", "pbrt_media", "pbrt_subsurface", "pbrt_nanovdb", "pbrt_motion"] {
        let scene = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!("scenes/{name}.pbrt"));
        let r = neumann().arg("render").arg(&scene).args(["--res", "24x16", "--spp", "2", "--quiet", "-o"]).arg(&out).output().unwrap();
        let stdout = String::from_utf8_lossy(&r.stdout);
        assert!(r.status.success(), "{name}: {stdout} {}", String::from_utf8_lossy(&r.stderr));
        assert!(stdout.contains("at 24x16") && stdout.contains("2 spp"), "{stdout}");
    }
    let bad = temp("bad.pbrt");
    std::fs::write(&bad, "WorldBegin\nShape \"sphere\" \"float radius\" [ 1 ] \"float raduis\" [ 2 ]\n").unwrap();
    let r = neumann().arg("render").arg(&bad).args(["--quiet", "-o"]).arg(&out).output().unwrap();
    let err = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(1), "{err}");
    assert!(err.contains("bad.pbrt:2:") && err.contains("unused parameter \"float raduis\""), "{err}");
}
