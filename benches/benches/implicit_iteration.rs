//! What one Newton iteration of the implicit driver costs, piece by piece,
//! on the hemisphere scene (scenes/hemisphere-0-90.toml, 40 × 40 cells:
//! 1 681 nodes, 5 043 dofs) in a state advanced into the stroke by the
//! explicit driver (so the membranes are sheared and the tangent's values
//! are a forming state's):
//!
//! - `assemble`: K̂ = c·M + sym(K) from the element tangents
//!   ([`SparseTangent::assemble`]);
//! - `factorise`: the numeric Cholesky with the run's symbolic analysis;
//! - `solve`: one forward/back substitution (what one product of the
//!   condensed contact solve costs, besides its rows);
//! - the same factorisation and solve with faer's simplicial and its
//!   supernodal kernels forced, with nnz(L) of each ordering.
//!
//! Printed as a table (best of `--repeat N` runs, default 20), not through
//! criterion: the pieces are timed in a one-thread rayon pool by
//! `DRAPE_BENCH_CLOCK` (thread CPU time on a shared machine). `--threads N`
//! times the assembly on N threads as well (wall time); `--assembly-only`
//! stops after the assembly (for a profiler).
//!
//! `cargo bench -p drape-benches --bench implicit_iteration`.

use std::path::Path;
use std::time::Duration;

use drape_benches::{Clock, Stopwatch};
use drape_io::scene::Scene;
use drape_time::tangent::SparseTangent;
use drape_time::{Explicit, ExplicitSettings, NoObserver};
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LltRef, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::sparse::linalg::{SupernodalThreshold, SymbolicSupernodalParams};
use faer::{Conj, MatMut, Par, Side};

/// Explicit steps before the measured state (about 0.3 s of the stroke).
const WARM_STEPS: u64 = 15_000;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let arg = |name: &str| {
        args.iter()
            .position(|a| a == name)
            .and_then(|k| args.get(k + 1))
            .map(|v| v.parse::<usize>().expect("a count"))
    };
    let repeat = arg("--repeat").unwrap_or(20);
    let threads = arg("--threads");
    // `--assembly-only`: stop after timing the assembly (for a profiler).
    let assembly_only = args.iter().any(|a| a == "--assembly-only");
    let clock = Clock::from_env();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("benches/ sits in the workspace");
    let path = root.join("scenes/hemisphere-0-90.toml");
    let scene = Scene::from_file(&path, &[]).expect("the hemisphere scene");
    let model = &scene.model;
    let mut state = model.initial_state();
    let mut driver = Explicit::new(
        model,
        ExplicitSettings {
            max_steps: Some(WARM_STEPS),
            ..scene.settings.clone()
        },
    )
    .expect("driver");
    driver
        .run(&mut state, &mut NoObserver)
        .expect("the warm-up run");
    // The run's scaled masses (the scene sets mass_scaling_dt).
    let mass = driver.mass().to_vec();
    let n = 3 * model.node_count();
    // An increment of 5 ms with the Bossak–Newmark β of ρ∞ = 0.
    let (h, beta) = (5e-3, 0.25);
    let mass_factor = 1.0 / (beta * h * h);
    let mut tangent = SparseTangent::new(model, vec![false; n]).expect("tangent");
    let one = pool(1);
    let best = |f: &mut dyn FnMut()| -> Duration {
        (0..repeat)
            .map(|_| {
                let watch = Stopwatch::start(clock);
                f();
                watch.elapsed()
            })
            .min()
            .unwrap_or_default()
    };
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    let assemble = one.install(|| {
        best(&mut || {
            tangent
                .assemble(model, &state.x, &state.history, h, &mass, mass_factor)
                .expect("assembly")
        })
    });
    println!(
        "hemisphere 40×40 at t = {:.3} s: {} dofs, nnz(K̂ upper) {}, clock {clock:?}, best of {repeat}",
        state.time,
        n,
        tangent.nonzeros()
    );
    println!("  assemble (1 thread)            {:>8.3} ms", ms(assemble));
    if let Some(t) = threads {
        let many = pool(t).install(|| {
            best(&mut || {
                tangent
                    .assemble(model, &state.x, &state.history, h, &mass, mass_factor)
                    .expect("assembly")
            })
        });
        println!("  assemble ({t} threads, wall)    {:>8.3} ms", ms(many));
    }
    if assembly_only {
        return;
    }
    let factorise = one.install(|| {
        best(&mut || {
            assert_eq!(
                tangent.factorise().expect("factorisation"),
                drape_time::tangent::Factorisation::Cholesky
            );
        })
    });
    let rhs: Vec<f64> = (0..n).map(|i| ((i * 7 + 3) % 11) as f64 - 5.0).collect();
    let mut z = rhs.clone();
    let solve = one.install(|| {
        best(&mut || {
            z.copy_from_slice(&rhs);
            tangent.solve(&mut z);
        })
    });
    println!(
        "  factorise (run's symbolic: {}, nnz(L) {})  {:>8.3} ms",
        kind(tangent.symbolic()),
        tangent.symbolic().len_val(),
        ms(factorise)
    );
    println!("  solve, 1 rhs (run's symbolic)  {:>8.3} ms", ms(solve));
    let matrix = tangent.matrix();
    let nd = nested_dissection(&tangent, &model.x0);
    let inverse = {
        let mut inv = vec![0usize; n];
        for (k, &d) in nd.iter().enumerate() {
            inv[d] = k;
        }
        inv
    };
    // Supernode amalgamation: faer's default, a tighter one, none.
    let tight: &[(usize, f64)] = &[(4, 1.0), (16, 0.4), (48, 0.05), (usize::MAX, 0.02)];
    for (name, threshold, ordering, relax) in [
        (
            "simplicial",
            SupernodalThreshold::FORCE_SIMPLICIAL,
            "AMD",
            "-",
        ),
        (
            "supernodal",
            SupernodalThreshold::FORCE_SUPERNODAL,
            "AMD",
            "default",
        ),
        (
            "supernodal",
            SupernodalThreshold::FORCE_SUPERNODAL,
            "AMD",
            "tight",
        ),
        (
            "supernodal",
            SupernodalThreshold::FORCE_SUPERNODAL,
            "AMD",
            "none",
        ),
        (
            "simplicial",
            SupernodalThreshold::FORCE_SIMPLICIAL,
            "ND",
            "-",
        ),
        (
            "supernodal",
            SupernodalThreshold::FORCE_SUPERNODAL,
            "ND",
            "default",
        ),
    ] {
        let symbolic = factorize_symbolic_cholesky(
            matrix.symbolic(),
            Side::Upper,
            if ordering == "AMD" {
                SymmetricOrdering::Amd
            } else {
                SymmetricOrdering::Custom(faer::perm::PermRef::new_checked(&nd, &inverse, n))
            },
            CholeskySymbolicParams {
                supernodal_flop_ratio_threshold: threshold,
                supernodal_params: SymbolicSupernodalParams {
                    relax: match relax {
                        "tight" => Some(tight),
                        "none" => None,
                        _ => SymbolicSupernodalParams::default().relax,
                    },
                },
                ..Default::default()
            },
        )
        .expect("symbolic");
        let mut stack = MemBuffer::new(StackReq::any_of(&[
            symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()),
            symbolic.solve_in_place_scratch::<f64>(1, Par::Seq),
        ]));
        let mut values = vec![0.0; symbolic.len_val()];
        let factor = best(&mut || {
            symbolic
                .factorize_numeric_llt(
                    &mut values,
                    matrix,
                    Side::Upper,
                    LltRegularization::default(),
                    Par::Seq,
                    MemStack::new(&mut stack),
                    Default::default(),
                )
                .expect("positive definite");
        });
        let solve = best(&mut || {
            z.copy_from_slice(&rhs);
            LltRef::new(&symbolic, &values).solve_in_place_with_conj(
                Conj::No,
                MatMut::from_column_major_slice_mut(&mut z, n, 1),
                Par::Seq,
                MemStack::new(&mut stack),
            );
        });
        println!(
            "  {name:<10} {ordering:<3} relax {relax:<7}: nnz(L) {:>8}, factorise {:>8.3} ms, solve {:>8.3} ms",
            symbolic.len_val(),
            ms(factor),
            ms(solve)
        );
    }
}

/// A nested-dissection ordering of the dofs from the nodes' reference
/// positions: the node set is cut at the median of its longer extent, the
/// nodes of one side next to the other are the separator, ordered last;
/// each node's three dofs stay together.
fn nested_dissection(tangent: &SparseTangent, x0: &[nalgebra::Vector3<f64>]) -> Vec<usize> {
    let nodes = x0.len();
    let m = tangent.matrix();
    let (ptr, rows) = (m.symbolic().col_ptr(), m.symbolic().row_idx());
    let mut adjacent = vec![Vec::new(); nodes];
    for j in 0..nodes {
        for &i in &rows[ptr[3 * j]..ptr[3 * j + 1]] {
            let i = i / 3;
            if i != j {
                adjacent[i].push(j);
                adjacent[j].push(i);
            }
        }
    }
    fn dissect(
        set: Vec<usize>,
        x0: &[nalgebra::Vector3<f64>],
        adjacent: &[Vec<usize>],
        side: &mut [u8],
        out: &mut Vec<usize>,
    ) {
        if set.len() <= 32 {
            out.extend(set);
            return;
        }
        let extent = |k: usize| {
            let (lo, hi) = set.iter().fold((f64::MAX, f64::MIN), |(lo, hi), &i| {
                (lo.min(x0[i][k]), hi.max(x0[i][k]))
            });
            hi - lo
        };
        let axis = if extent(0) >= extent(1) { 0 } else { 1 };
        let mut sorted = set.clone();
        sorted.sort_by(|&a, &b| x0[a][axis].total_cmp(&x0[b][axis]).then(a.cmp(&b)));
        let median = x0[sorted[sorted.len() / 2]][axis];
        for &i in &set {
            side[i] = if x0[i][axis] < median { 1 } else { 2 };
        }
        let mut left = Vec::new();
        let mut right = Vec::new();
        let mut separator = Vec::new();
        for &i in &set {
            if side[i] == 1 {
                left.push(i);
            } else if adjacent[i].iter().any(|&j| side[j] == 1) {
                separator.push(i);
            } else {
                right.push(i);
            }
        }
        for &i in &set {
            side[i] = 0;
        }
        if left.is_empty() || right.is_empty() {
            out.extend(set);
            return;
        }
        dissect(left, x0, adjacent, side, out);
        dissect(right, x0, adjacent, side, out);
        out.extend(separator);
    }
    let mut order = Vec::with_capacity(nodes);
    let mut side = vec![0u8; nodes];
    dissect((0..nodes).collect(), x0, &adjacent, &mut side, &mut order);
    order
        .iter()
        .flat_map(|&i| [3 * i, 3 * i + 1, 3 * i + 2])
        .collect()
}

fn kind(symbolic: &SymbolicCholesky<usize>) -> &'static str {
    match symbolic.raw() {
        SymbolicCholeskyRaw::Simplicial(_) => "simplicial",
        SymbolicCholeskyRaw::Supernodal(_) => "supernodal",
    }
}

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a rayon pool")
}
