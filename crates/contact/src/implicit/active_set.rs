//! The contact side of `contact_solver = "active_set"`: normal contact as a
//! primal–dual active set (Hüeber–Stadler–Wohlmuth), taken inside the
//! driver's Newton iteration as a semi-smooth Newton method, so that each
//! iteration solves one linear system, the saddle-point system
//!
//! ```text
//! [K̂   Cᵀ] [ Δx]   [ r + springs' forces]
//! [C  −D ] [−λ ] = [ −g                  ]
//! ```
//!
//! over the rows held as equalities, with λ = 0 on the others. The driver
//! assembles and factorises it (`drape_time::saddle`); this module decides
//! which rows it holds and takes its solution back into the pairs.
//!
//! **The active set.** A normal row is held when λ − c·g > 0, with λ its
//! signed multiplier from the last system and g its gap at the iterate
//! (the semi-smooth Newton step on the complementarity function
//! λ − max(0, λ − c·g)); c = 1/A_kk, A_kk ≈ nᵀ·K̂_ii⁻¹·n the row's
//! compliance from the node's 3 × 3 block, so that λ and c·g are forces of
//! the same size. A row whose multiplier came out negative leaves at the
//! next iteration (its clamped λ_N = 0 leaves a residual the driver sees);
//! a penetrating row enters. Where the set no longer changes, the
//! iteration is Newton's on a smooth system, quadratic where the tangent
//! is exact (see the driver's tests).
//!
//! **Friction** is the condensed solver's: the return mapping of
//! `update_friction` between iterations, stick as the regularised springs
//! in K̂ (or rigid rows: equalities here), slip as μ·λ_N from the last
//! system with its turn row. That is the stick/slip active set of
//! Hüeber–Stadler–Wohlmuth with the stick regularised, chosen over
//! Alart–Curnier's augmented Lagrangian because the latter's generalised
//! Jacobian couples the slip force to λ_N (μ·d·∂λ_N): not symmetric, so no
//! symmetric factorisation (faer's sparse LU of the shipped hemisphere's
//! matrix takes 4× its Cholesky); here the slip force lags one iteration
//! behind λ_N, as in the condensed solver, and a slipping pair converges
//! linearly in that term.
//!
//! **A step that would jump a contact.** The semi-smooth step trusts the
//! set of the last iterate; a force-driven holder with no row held moves
//! by its force over its inertia alone, which can carry it metres through
//! the blank in one step (deep drawing: 5.8 m at the first contact), and a
//! node or tool that far past its contact is no longer a pair the next
//! linearisation finds. When the step's linearised gaps put a row that was
//! not held deeper than half the margin into its tool, the driver solves
//! again on the same linearisation with the set those gaps ask for (a
//! primal–dual active-set iteration, one factorisation each), so that the
//! step never crosses what the margin can see.
//!
//! **Pinched nodes and the force-driven holder.** A node between the holder
//! and the die holds two rows ±n; over several such nodes the rows are
//! dependent (how the clamping force is shared among them is
//! indeterminate), so [C 0] alone would make the system singular. Every
//! rigid row gets a small compliance ε = [`REGULARISATION`]·A_kk on its
//! diagonal, which makes the matrix quasi-definite (the driver eliminates
//! the rows onto the nodes, K̂ + Cᵀ·D⁻¹·C, with no zero pivot) and picks
//! the least-squares share; the driver then removes ε's bias by iterative
//! refinement against the unregularised system. With friction each row
//! has its own cone, μ times its share, so the share must not move
//! between iterations: after each solve the clamp of a force-driven
//! tool's flat face is shared among the nodes it pinches in proportion
//! to their masses (`share_clamp`: a uniform clamping pressure; the step
//! and Cᵀλ are unchanged). Left to the least-squares share, the
//! deep-drawing runs chattered between stick and slip from t ≈ 0.21 s
//! and did not complete. A node the fabric lifts off the die harder than
//! its share presses it takes more than its share, so that no row pulls
//! (see `share_clamp`). Where the two tools' normals at a node lean alike
//! by up to 1.4e-3 rad (a holder's rounded edge over a die's fillet), or
//! with friction by less than sin θ = μ₁ + μ₂, they are made exactly
//! opposite (`ImplicitContact::square_pinches`): left leaning, the two
//! rows carried tangential forces through the lean, with multipliers of
//! −5·10⁴ N on a 45 N clamp, and with the slip forces one iteration
//! behind, the holder's whole clamp moved onto its edge's nodes. A
//! force-driven holder is one more unknown (its displacement along its
//! axis, its inertia on the diagonal), coupled to every row of its pairs.
//!
//! **The pattern** is fixed per set of candidates (nodes inside a tool's
//! grown box at the start of an increment): [`SLOTS_PER_PAIR`] slots per
//! candidate (a normal row, two tangential), each coupled to its node's
//! three components and its tool's unknown. A slot not held is a decoupled
//! −1 on the diagonal.

use super::*;

/// Slots of the active-set system per candidate (node, tool): the normal
/// row and at most two tangential rows (rigid stick, or a compliant row
/// coupled to a force-driven tool; regularised stick rows of a node alone
/// are springs in K̂).
pub const SLOTS_PER_PAIR: usize = 3;

/// The compliance given to a rigid row, relative to its own A_kk: small
/// enough that the refinement removes its bias in one or two solves,
/// large enough that the factorisation's pivots stay above round-off.
pub const REGULARISATION: f64 = 1e-8;

/// An equation of the active-set system: C's row on a node (and a tool),
/// t·Δx + a·Δd − compliance·(−λ) = −target.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SystemRow {
    /// Its slot (see [`ImplicitContact::slots`]).
    pub slot: usize,
    /// The pair it belongs to (for [`ImplicitContact::finish_active_set`]).
    pub pair: u32,
    /// Its node.
    pub node: u32,
    /// The row on the node's three components.
    pub direction: Vector3<f64>,
    /// Its tool.
    pub tool: u32,
    /// The row on the tool's displacement (force-driven tools only).
    pub tool_coefficient: f64,
    /// Its compliance (mm/N): 1/k_t of a regularised stick row, 0 for a
    /// rigid one.
    pub compliance: f64,
    /// The regularisation added to the compliance in the factorised
    /// matrix (see [`REGULARISATION`]), which the refinement removes.
    pub regularisation: f64,
    /// Its value at the iterate: a gap or a slip component (mm).
    pub target: f64,

    /// A normal row (λ ≥ 0).
    pub bounded: bool,
}

impl ImplicitContact {
    /// (tool, node, λ_N) of every pair of the last solve, condensed or
    /// active-set, in the pairs' order.
    pub fn normal_forces(&self) -> impl Iterator<Item = (u32, u32, f64)> + '_ {
        self.pairs.iter().map(|p| (p.tool, p.node, p.lambda))
    }

    /// Changes whenever the candidates (and so the active-set system's
    /// pattern) change.
    pub fn candidate_generation(&self) -> u64 {
        self.candidate_generation
    }

    /// The slots of the active-set system, in order: (node, tool) of each,
    /// [`SLOTS_PER_PAIR`] per candidate, tool after tool.
    pub fn slots(&self) -> impl Iterator<Item = (u32, u32)> + '_ {
        self.candidates.iter().enumerate().flat_map(|(t, c)| {
            c.iter()
                .flat_map(move |&i| std::iter::repeat_n((i, t as u32), SLOTS_PER_PAIR))
        })
    }

    /// The stiffness and the residual of tool `t`'s unknown when it is
    /// force-driven (its inertia, its applied force less its inertia
    /// force), None for a tool that moves as prescribed.
    pub fn tool_equation(&self, t: usize) -> Option<(f64, f64)> {
        self.tools[t]
            .is_force_driven()
            .then(|| (self.tool_stiffness(t), self.tool_residual(t)))
    }

    /// Adds the springs' forces at the iterate (see
    /// [`Self::set_springs_in_tangent`]) to the residual `r` (3·N).
    pub fn add_spring_forces(&self, r: &mut [f64]) {
        for row in &self.springs {
            let i = 3 * self.pairs[row.pair as usize].node as usize;
            let force = -row.target / row.compliance;
            for c in 0..3 {
                r[i + c] += row.direction[c] * force;
            }
        }
    }

    /// The rows the next system holds as equalities, into `out`: every
    /// tangential row left in C, and the normal rows whose λ − c·g > 0
    /// (see the module's documentation); `block(i)` is K̂'s 3 × 3 block at
    /// node i (with the springs). With `linearised`, g is the linearised
    /// gap after the last system instead of the gap at the iterate: a
    /// primal–dual active-set iteration on one linearisation, which ends
    /// at the condensed solve's answer (the tests' reference). Changes
    /// nothing in the pass.
    pub fn active_set_rows(
        &self,
        block: &dyn Fn(usize) -> Matrix3<f64>,
        linearised: bool,
        out: &mut Vec<SystemRow>,
    ) {
        out.clear();
        let slot_of = |pair: &Pair| -> usize {
            let t = pair.tool as usize;
            let before: usize = self.candidates[..t].iter().map(Vec::len).sum();
            let c = self.candidates[t]
                .binary_search(&pair.node)
                .expect("a pair's node is a candidate of its tool");
            SLOTS_PER_PAIR * (before + c)
        };
        let mut last: Option<(u32, usize, usize, Matrix3<f64>)> = None;
        for row in &self.rows {
            let pair = &self.pairs[row.pair as usize];
            // The pair's first row is its normal one; the tangential ones
            // follow in the next slots.
            let (base, k, inverse) = match last {
                Some((p, base, k, b)) if p == row.pair => (base, k + 1, b),
                _ => (
                    slot_of(pair),
                    0,
                    block(pair.node as usize)
                        .try_inverse()
                        .unwrap_or_else(Matrix3::zeros),
                ),
            };
            last = Some((row.pair, base, k, inverse));
            debug_assert!(k < SLOTS_PER_PAIR);
            let t = pair.tool as usize;
            let tool = match self.tool_equation(t) {
                Some((stiffness, _)) => row.tool_coefficient * row.tool_coefficient / stiffness,
                None => 0.0,
            };
            let a_kk = row.direction.dot(&(inverse * row.direction)) + tool;
            let a_kk = if a_kk.is_finite() && a_kk > 0.0 {
                a_kk
            } else {
                1.0
            };
            let gap = if linearised {
                pair.predicted
            } else {
                row.target
            };
            let held = !row.bounded || pair.multiplier - gap / a_kk > 0.0;
            if !held {
                continue;
            }
            out.push(SystemRow {
                slot: base + k,
                pair: row.pair,
                node: pair.node,
                direction: row.direction,
                tool: pair.tool,
                tool_coefficient: row.tool_coefficient,
                compliance: row.compliance,
                regularisation: if row.compliance > 0.0 {
                    0.0
                } else {
                    REGULARISATION * a_kk
                },
                target: row.target,
                bounded: row.bounded,
            });
        }
    }

    /// Shares the clamp of a force-driven tool's flat face among the nodes
    /// it pinches against another tool in proportion to their masses
    /// (their share of the fabric where the mesh is uniform): a uniform
    /// clamping pressure, as a rigid flat holder on a fabric of uniform
    /// thickness gives.
    ///
    /// Why: with two held rows ±n on each such node, only the holder's
    /// total and each node's net normal force λ_d − λ_h are determined;
    /// the rest is a null space of the system, where the solve's answer
    /// (the regularisation's least-squares share, see [`REGULARISATION`])
    /// moved with every iteration's K̂ (Σ|Δλ| 5·10⁴ N of a 3.8·10⁵ N
    /// clamp in one iteration of the deep drawing 10 × 10 with no row
    /// entering or leaving). Each pinched node's friction cone is μ times
    /// its share, so the nodes at the edge of the cone flipped between
    /// stick and slip in turn and the deep drawings did not complete. Kept
    /// at the last solve's share instead (a proximal term towards the last
    /// multipliers), the clamp drifted onto a few nodes (two nodes carried
    /// it all by t = 0.24 s). Moving λ along that null space leaves Cᵀλ,
    /// the holder's force and so the step unchanged.
    ///
    /// A node the fabric pulls off the die harder than its share presses
    /// it (λ_d − λ_h < −share) takes more than its share, λ_h − λ_d, so
    /// that neither row's multiplier is negative: the rest of the clamp is
    /// shared among the others at a lower pressure. With the plain share
    /// such a node's die row came out negative, left the set, came back
    /// pressed, and so on: on the shipped hemisphere-ring the die rows at
    /// the clamp's inner edge cycled that way from t ≈ 0.41 s, the
    /// increments fell to 1e-5 s and the run failed at t ≈ 0.49 s.
    ///
    /// Only rows both held whose normals are opposite to round-off, the
    /// holder's along its axis (its flat face): elsewhere (a rounded edge,
    /// squared pairs included) the rows are not dependent, or the node
    /// has more room than the flat faces' clamp, and the system's share
    /// stands.
    pub(super) fn share_clamp(&mut self) {
        let pairs = &mut self.pairs;
        for (h, holder) in self.tools.iter().enumerate() {
            if !holder.is_force_driven() {
                continue;
            }
            let axis = holder.motion.direction();
            let range = |pairs: &[Pair], t: usize| {
                let start = pairs.partition_point(|p| (p.tool as usize) < t);
                let end = pairs.partition_point(|p| (p.tool as usize) <= t);
                start..end
            };
            let held = range(pairs, h);
            for d in (0..self.tools.len()).filter(|&d| d != h) {
                let other = range(pairs, d);
                // The node's pair on tool d when the node is pinched.
                let partner = |pairs: &[Pair], k: usize| -> Option<usize> {
                    let p = &pairs[k];
                    if !p.active || p.squared || p.normal.dot(&axis) < 1.0 - FLAT {
                        return None;
                    }
                    let j = other.start
                        + pairs[other.clone()]
                            .binary_search_by_key(&p.node, |q| q.node)
                            .ok()?;
                    let q = &pairs[j];
                    (q.active && p.normal.dot(&q.normal) < -1.0 + FLAT).then_some(j)
                };
                let weight = |node: u32| self.mass.get(node as usize).copied().unwrap_or(1.0);
                // A node's least share: what keeps both its rows pressed,
                // λ_h ≥ 0 and λ_d = λ_h + net ≥ 0.
                let least = |pairs: &[Pair], k: usize, j: usize| {
                    (pairs[k].multiplier - pairs[j].multiplier).max(0.0)
                };
                let (mut clamp, mut total, mut least_total) = (0.0, 0.0, 0.0);
                for k in held.clone() {
                    if let Some(j) = partner(pairs, k) {
                        clamp += pairs[k].multiplier;
                        total += weight(pairs[k].node);
                        least_total += least(pairs, k, j);
                    }
                }
                // No share keeps every row pressed: the system's stands.
                if total <= 0.0 || least_total > clamp {
                    continue;
                }
                // The pressure p of the shares max(w·p, least) that add up
                // to the clamp. From the plain share, which is not below
                // it, each pass binds the nodes whose least share is above
                // w·p and solves for p with them bound: p falls, the bound
                // set only grows, and a pass that binds no new node has p.
                let mut pressure = clamp / total;
                loop {
                    let (mut bound, mut free) = (0.0, 0.0);
                    for k in held.clone() {
                        if let Some(j) = partner(pairs, k) {
                            let (w, l) = (weight(pairs[k].node), least(pairs, k, j));
                            if l > w * pressure {
                                bound += l;
                            } else {
                                free += w;
                            }
                        }
                    }
                    let next = if free > 0.0 {
                        (clamp - bound) / free
                    } else {
                        0.0
                    };
                    if next >= pressure {
                        break;
                    }
                    pressure = next;
                }
                for k in held.clone() {
                    let Some(j) = partner(pairs, k) else {
                        continue;
                    };
                    let share = (weight(pairs[k].node) * pressure).max(least(pairs, k, j));
                    let net = pairs[j].multiplier - pairs[k].multiplier;
                    for (m, value) in [(k, share), (j, share + net)] {
                        pairs[m].multiplier = value;
                        pairs[m].lambda = value.max(0.0);
                    }
                }
            }
        }
    }

    /// The deepest linearised penetration (mm, ≥ 0) after the last
    /// active-set system among the normal rows it did not hold: how far
    /// the step would carry a node into a tool whose row was left out.
    pub fn unheld_penetration(&self) -> f64 {
        self.pairs
            .iter()
            .filter(|p| !p.active)
            .map(|p| -p.predicted)
            .fold(0.0, f64::max)
    }

    /// Takes the system's solution back: Δx in `dx` (3·N, its springs'
    /// forces from it), the multipliers `lambda` of `rows` (λ, not −λ),
    /// each tool's Δd in `tool_step` (zero for a prescribed one). Returns
    /// the solve's counts, `active_changes` being the normal rows that
    /// entered or left the set against the last system.
    pub fn finish_active_set(
        &mut self,
        rows: &[SystemRow],
        lambda: &[f64],
        tool_step: &[f64],
        dx: &[f64],
    ) -> SolveStats {
        let mut changes = 0usize;
        let mut held = std::mem::take(&mut self.scratch.bounded);
        held.clear();
        held.resize(self.pairs.len(), false);
        for row in rows.iter().filter(|r| r.bounded) {
            held[row.pair as usize] = true;
        }
        for (pair, &h) in self.pairs.iter_mut().zip(&held) {
            if pair.active != h {
                changes += 1;
            }
            pair.active = h;
            pair.lambda_before = pair.lambda;
            pair.lambda = 0.0;
            pair.multiplier = 0.0;
            pair.stick = Vector3::zeros();
        }
        self.scratch.bounded = held;
        for (row, &l) in rows.iter().zip(lambda) {
            let pair = &mut self.pairs[row.pair as usize];
            if row.bounded {
                pair.multiplier = l;
                pair.lambda = l.max(0.0);
            } else {
                pair.stick += row.direction * l;
            }
        }
        self.share_clamp();
        self.add_spring_sticks(dx);
        for pair in &mut self.pairs {
            let tool = &self.tools[pair.tool as usize];
            let i = 3 * pair.node as usize;
            let n = pair.normal;
            let along = n.x * dx[i] + n.y * dx[i + 1] + n.z * dx[i + 2];
            let moved = if tool.is_force_driven() {
                -n.dot(&tool.motion.direction()) * tool_step[pair.tool as usize]
            } else {
                0.0
            };
            pair.predicted = pair.gap + along + moved;
        }
        for (t, step) in self.tool_step.iter_mut().enumerate() {
            *step = if self.tools[t].is_force_driven() {
                tool_step[t]
            } else {
                0.0
            };
        }
        let stats = SolveStats {
            iterations: 1,
            rows: rows.len(),
            active: self.pairs.iter().filter(|p| p.lambda > 0.0).count(),
            active_changes: changes,
            ..SolveStats::default()
        };
        self.solve_totals.add(&stats);
        stats
    }
}
