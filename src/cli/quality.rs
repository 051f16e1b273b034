//! `solidtex quality`: slice energy, histogram distance and layered measures of a volume.

use crate::error::{Error, Result};
use crate::io;
use crate::quality::{self, Report};
use std::path::PathBuf;

/// The arguments of `solidtex quality`.
#[derive(Debug, clap::Args)]
pub struct QualityArgs {
    /// The volume to measure.
    pub volume: PathBuf,
    /// The exemplar it was made from (Ex, or the layered exemplar).
    #[arg(long, required_unless_present_any = ["labels", "truth"])]
    pub exemplar: Option<PathBuf>,
    /// Measure a label volume instead (a few phases in the first channel): per phase its
    /// share, two-point probability S2 and lineal path per axis, and interface per voxel.
    #[arg(long, conflicts_with = "exemplar")]
    pub labels: bool,
    /// With --labels: the 3D label volume the volume should match (its values are snapped
    /// to the truth's labels first); prints each phase's figures as volume over truth.
    #[arg(long)]
    pub truth: Option<PathBuf>,
    /// Exit with status 1 when any figure is outside its band (docs/synthesis.md,
    /// "Checking a volume"), naming each; with --labels it needs --truth.
    #[arg(long)]
    pub check: bool,
    /// Ey, Ez and shrinking.
    #[command(flatten)]
    pub others: super::synth::OtherExemplars,
    /// Measure as a layered volume (x and y only, plus depth and sweeping measures);
    /// the default when the volume's type is 1-b.
    #[arg(long)]
    pub layered: bool,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// Run `solidtex quality`.
pub fn run(args: &QualityArgs) -> Result<()> {
    args.others.check()?;
    if args.truth.is_some() && !args.labels {
        return Err(crate::Error::usage(
            "--truth compares label volumes: give --labels with it (quality VOLUME --labels --truth TRUTH)",
        ));
    }
    let exemplar_options = [
        ("--ey", args.others.ey.is_some()),
        ("--ez", args.others.ez.is_some()),
        ("--max-exemplar", args.others.max_exemplar.is_some()),
        ("--layered", args.layered),
    ];
    if let Some((name, _)) = exemplar_options.iter().find(|(_, given)| args.labels && *given) {
        return Err(crate::Error::usage(format!(
            "{name} belongs to measuring against exemplars; --labels measures the volume's phases (against --truth \
             TRUTH), reading no exemplar"
        )));
    }
    if args.check && args.labels && args.truth.is_none() {
        return Err(crate::Error::usage(
            "--check with --labels needs --truth TRUTH: without a truth no figure has a band",
        ));
    }
    let volume = io::read_volume(&args.volume, io::budget_from_env()?)?;
    let Some(exemplar) = &args.exemplar else { return labels(args, &volume) };
    let others = shrunk_as_made(&args.others, &volume);
    let ex = others.load(exemplar, "exemplar")?;
    let (ey, ez) = others.load_yz()?;
    others.check_channels((exemplar, &ex), (ey.as_ref(), ez.as_ref()))?;
    let given = [(exemplar.as_path(), Some(&ex)), (others.ey.as_deref().unwrap_or(exemplar), ey.as_ref())];
    for (path, image) in given.into_iter().chain([(others.ez.as_deref().unwrap_or(exemplar), ez.as_ref())]) {
        let least = crate::quality::LEAST_EXEMPLAR;
        if let Some(image) = image.filter(|i| i.width() < least || i.height() < least) {
            return Err(crate::Error::file(
                path,
                format!(
                    "is {}x{} pixels (as loaded); measuring needs an exemplar of at least {least}x{least} pixels",
                    image.width(),
                    image.height()
                ),
            ));
        }
    }
    let layered = args.layered || volume.meta.texture_type == Some(crate::TextureType::T1b);
    let ey_ref = ey.as_ref().unwrap_or(&ex);
    let exemplars = if layered {
        [Some(&ex), Some(&ex), None]
    } else {
        [Some(&ex), Some(ey_ref), Some(ez.as_ref().unwrap_or(ey_ref))]
    };
    let report = quality::assess(&volume, exemplars, layered).map_err(|e| e.in_file(&args.volume))?;
    if !report.not_measured.is_empty() {
        let [x, y, z] = volume.dims();
        tell!(
            "note: {} is {x}x{y}x{z} voxels: the cuts across {} are smaller than {s}x{s} voxels, so their slice \
             energy, sharpness and line figures are not measured{}",
            args.volume.display(),
            quality::listed(&report.not_measured, "and"),
            if args.check { " nor checked" } else { "" },
            s = quality::SMALLEST_CUT
        );
    }
    if args.json {
        say!("{}", serde_json::to_string_pretty(&report).expect("a report always serializes"));
    } else {
        say!("{}", table(&report).trim_end());
    }
    verdict(args.check, report.outside_bands())
}

/// The exemplars' shrinking: `--max-exemplar` as given, else as the volume was synthesized
/// with (its provenance; said on stderr), so a volume is measured against the exemplars
/// it was made from.
fn shrunk_as_made(others: &super::synth::OtherExemplars, volume: &crate::Volume) -> super::synth::OtherExemplars {
    let recorded = volume.meta.get(super::synth::MAX_EXEMPLAR_KEY).and_then(|v| v.parse::<usize>().ok());
    let max_exemplar = match (others.max_exemplar, recorded) {
        (None, Some(side)) => {
            tell!(
                "measuring against the exemplars shrunk to {side} px, as the volume was made (--max-exemplar {side})"
            );
            Some(side)
        }
        (given, _) => given,
    };
    super::synth::OtherExemplars { ey: others.ey.clone(), ez: others.ez.clone(), max_exemplar }
}

/// With `--check`: an error (exit status 1) naming the figures outside their bands.
fn verdict(check: bool, outside: Vec<String>) -> Result<()> {
    if !check {
        return Ok(());
    }
    if outside.is_empty() {
        tell!("check: every figure is within its band");
        return Ok(());
    }
    tell!("check: outside their bands:");
    for figure in &outside {
        tell!("  {figure}");
    }
    Err(crate::Error::invalid(format!("check: {} figure(s) outside their bands (listed above)", outside.len())))
}

fn table(r: &Report) -> String {
    let mut out = String::from(
        "slice energy (8x8, r = 0.8; lower is better)\n  axis    volume    random  exemplar  volume/exemplar\n",
    );
    for a in &r.axes {
        out += &format!("  {:<4} {:>9.4} {:>9.4} {:>9.4} {:>16.2}\n", a.axis, a.volume, a.random, a.exemplar, a.ratio);
    }
    for a in r.axes.iter().filter(|a| !a.repeats.is_empty()) {
        let offsets: Vec<String> = a.repeats.iter().map(|o| format!("({}, {})", o[0], o[1])).collect();
        out += &format!(
            "  note: along {} the exemplar repeats itself at offsets {}; its baseline skips those copies \
             (with them: {:.4})\n",
            a.axis,
            offsets.join(", "),
            a.exemplar_with_copies.unwrap_or(a.exemplar)
        );
    }
    let (g, l) = (crate::sharpness::GRADIENT_RANGE, crate::sharpness::LENGTH_RANGE);
    out += &format!(
        "sharpness of the cuts at 1/4, 1/2, 3/4 against the exemplar (targets: gradient {}-{}, length {}-{})\n  \
         axis  gradient   length  gradient-histogram  exemplar length (px)\n",
        g.0, g.1, l.0, l.1
    );
    for s in &r.sharpness {
        out += &format!(
            "  {:<4} {:>9.2} {:>8.2} {:>19.3} {:>21.2}{}\n",
            s.axis,
            s.gradient_ratio,
            s.length_ratio,
            s.gradient_histogram_distance,
            s.exemplar_length,
            if s.in_range() { "" } else { "  (outside the targets)" }
        );
    }
    out += &lines_table(&r.lines);
    out += "histogram distance (L1 over 32 bins; 0 = equal, 2 = disjoint)\n";
    for h in &r.histograms {
        out += &format!("  {:<12} {:.4}\n", h.channel, h.distance);
    }
    if let Some(p) = &r.patches {
        out += &format!(
            "coherent patches (recorded by the synthesis; target: largest at most {} of the exemplar)\n  \
             coherent neighbour pairs {:.3}\n  largest patch           {:.3}\n",
            crate::synth::patches::LARGEST_PATCH_MOST,
            p.coherent_pairs,
            p.largest
        );
    }
    if let Some(l) = &r.layered {
        out += &format!(
            "layered\n  depth error     {:.4}\n  depth monotonic {}{}\n  sweeping index  {:.4} (share of voxels whose x and y matches coincide)\n",
            l.depth_error,
            l.depth_monotonic,
            if l.depth_monotonic {
                String::new()
            } else {
                format!(" (largest fall between slices {:.5})", l.depth_largest_drop)
            },
            l.sweeping_index
        );
    }
    out
}

/// `quality VOLUME --labels [--truth TRUTH]`: the materials statistics of a label volume,
/// and with a truth each phase's figures as volume over truth.
fn labels(args: &QualityArgs, volume: &crate::Volume) -> Result<()> {
    let Some(truth_path) = &args.truth else {
        let stats = crate::labels::measure(volume).map_err(|e| e.in_file(&args.volume))?;
        if args.json {
            say!("{}", serde_json::to_string_pretty(&stats).expect("statistics always serialize"));
        } else {
            say!("{}", label_table(&stats).trim_end());
        }
        return Ok(());
    };
    let truth = io::read_volume(truth_path, io::budget_from_env()?)?;
    for (path, dims) in [(&args.volume, volume.dims()), (truth_path, truth.dims())] {
        if dims.iter().any(|side| *side < crate::labels::LEAST_SIDE) {
            return Err(Error::file(
                path,
                format!(
                    "is {}x{}x{} voxels: comparing label volumes needs at least {} voxels along each axis of both",
                    dims[0],
                    dims[1],
                    dims[2],
                    crate::labels::LEAST_SIDE
                ),
            ));
        }
    }
    let comparison = crate::labels::against_truth(volume, &truth).map_err(|e| e.in_file(truth_path))?;
    if args.json {
        say!("{}", serde_json::to_string_pretty(&comparison).expect("statistics always serialize"));
    } else {
        say!("the volume, snapped to the truth's labels\n{}", label_table(&comparison.volume).trim_end());
        say!("the truth\n{}", label_table(&comparison.truth).trim_end());
        say!("{}", ratio_table(&comparison.ratios).trim_end());
    }
    verdict(args.check, comparison.outside_bands())
}

fn label_table(stats: &crate::labels::LabelStats) -> String {
    let [x, y, z] = stats.dims;
    let mut out = format!("label volume {x}x{y}x{z}: {} phase(s)\n", stats.phases.len());
    if stats.tiles > 1 {
        let [a, b, c] = stats.tile;
        out += &format!(
            "measured in {} tiles of {a}x{b}x{c} (the smaller of the two volumes' sides on each axis: pieces are cut \
             where a box ends), pooled\n",
            stats.tiles
        );
    }
    let length = |c: Option<f64>| c.map_or_else(|| "-".to_string(), |c| format!("{c:.1}"));
    for p in &stats.phases {
        out += &format!(
            "phase {}: share {:.4}, pieces {:.1} per 100k voxels ({:.1} of 1-2 voxels), correlation length x {} y {} z {}, \
             interface {:.4} per voxel (x {:.4}, y {:.4}, z {:.4})\n",
            p.label,
            p.share,
            p.pieces_per_100k,
            p.specks_per_100k,
            length(p.correlation_length[0]),
            length(p.correlation_length[1]),
            length(p.correlation_length[2]),
            p.interface_per_voxel,
            p.interface_per_axis[0],
            p.interface_per_axis[1],
            p.interface_per_axis[2]
        );
        for (a, axis) in ["x", "y", "z"].iter().enumerate() {
            let at = |v: &Vec<f64>| {
                [1, 2, 4, 8, 16]
                    .iter()
                    .filter_map(|r| v.get(*r).map(|s| format!("{s:.3}")))
                    .collect::<Vec<_>>()
                    .join(" ")
            };
            out += &format!("  {axis}: S2 at 1 2 4 8 16: {}   L: {}\n", at(&p.two_point[a]), at(&p.lineal_path[a]));
        }
    }
    out
}

fn ratio_table(ratios: &[crate::labels::PhaseAgainstTruth]) -> String {
    use crate::labels::{CORRELATION_BAND as C, MOST_EXTRA_SPECKS as M, PIECES_BAND as P, SHARE_BAND as S};
    let mut out = format!(
        "volume over truth (bands: share {}-{}, pieces {}-{}, correlation length {}-{}; specks: pieces of 1-2 voxels \
         per 100k, volume minus truth, at most {M})\n  phase      share  pieces  length x     y     z   specks\n",
        S.0, S.1, P.0, P.1, C.0, C.1
    );
    let length = |c: Option<f64>| c.map_or_else(|| "    -".to_string(), |c| format!("{c:>5.2}"));
    for r in ratios {
        out += &format!(
            "  {:<8} {:>7.2} {:>7.2}    {} {} {} {:>+7.1}\n",
            r.label,
            r.share_ratio,
            r.pieces_ratio,
            length(r.correlation_ratio[0]),
            length(r.correlation_ratio[1]),
            length(r.correlation_ratio[2]),
            r.extra_specks_per_100k
        );
    }
    out
}

/// The line structure rows of `quality` (docs/synthesis.md, "Line structure").
fn lines_table(lines: &[crate::lines::Lines]) -> String {
    let mut out = String::from(
        "line structure of the cuts against the exemplar (cuts over exemplar; targets: pieces 0.7-1.3, top-3 share \
         at least 0.8, line share 0.5-1.5)\n  axis  lines  pieces  top-3  share   exemplar: pieces/1000 px, top-3 \
         share (window spread of pieces, top-3)\n",
    );
    for l in lines {
        let p = &l.lines;
        if !l.applies {
            out += &format!(
                "  {:<4}  no line structure to keep (the exemplar's longest {} lines hold {:.2} of its line pixels, \
                 under {})\n",
                l.axis,
                p.name,
                p.exemplar.top3_share,
                crate::lines::APPLIES
            );
            continue;
        }
        out += &format!(
            "  {:<4} {:>6} {:>7.2} {:>6.2} {:>6.2}   {:.2}, {:.2} ({:.2}-{:.2}, {:.2}-{:.2})\n",
            l.axis,
            p.name,
            p.pieces_ratio,
            p.top3_ratio,
            p.share_ratio,
            p.exemplar.pieces_per_1000,
            p.exemplar.top3_share,
            p.pieces_spread.0,
            p.pieces_spread.1,
            p.top3_spread.0,
            p.top3_spread.1
        );
    }
    out
}

/// The arguments of `solidtex noise`.
#[derive(Debug, clap::Args)]
pub struct NoiseArgs {
    /// The exemplar (Ex; alone, all three axes).
    pub exemplar: PathBuf,
    /// Ey, Ez and shrinking.
    #[command(flatten)]
    pub others: super::synth::OtherExemplars,
    /// Size: N for a cube, or XxYxZ.
    #[arg(long, default_value = "64")]
    pub size: String,
    /// Seed of the noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// The volume file to write.
    #[arg(short, long)]
    pub output: PathBuf,
}

/// Run `solidtex noise`: the control volume of `crate::controls::spectral_noise`.
pub fn noise(args: &NoiseArgs) -> Result<()> {
    args.others.check()?;
    let dims = super::commands::parse_size(&args.size)?;
    let mut inputs = vec![args.exemplar.as_path()];
    inputs.extend(args.others.ey.as_deref());
    inputs.extend(args.others.ez.as_deref());
    io::check_output(&args.output, &inputs)?;
    let ex = args.others.load(&args.exemplar, "exemplar")?;
    let (ey, ez) = args.others.load_yz()?;
    args.others.check_channels((&args.exemplar, &ex), (ey.as_ref(), ez.as_ref()))?;
    crate::volume::check_size(dims, ex.channel_count(), io::budget_from_env()?).map_err(super::commands::usage)?;
    let ey_ref = ey.as_ref().unwrap_or(&ex);
    let exemplars = [Some(&ex), Some(ey_ref), Some(ez.as_ref().unwrap_or(ey_ref))];
    let mut volume =
        crate::controls::spectral_noise(exemplars, dims, args.seed).map_err(|e| e.in_file(&args.exemplar))?;
    if let Some(side) = args.others.max_exemplar {
        volume.meta.set(super::synth::MAX_EXEMPLAR_KEY, side.to_string());
    }
    super::write_volume(&args.output, &volume)?;
    tell!("wrote {} (random-phase noise with the exemplars' spectra and colours)", args.output.display());
    Ok(())
}
