//! What each validation case checks and against what, in one line each,
//! for `docs/validation.md` (the tolerances and results come from the run).
//! A case without a line here fails `every_case_is_described`: a new case
//! adds its line with its `Case` entry.

/// (what the case checks, its reference) for a case name.
pub fn describe(name: &str) -> Option<(&'static str, &'static str)> {
    Some(match name {
        "plies/sled" => (
            "a ply pulled over a held ply under a normal load N (μ = 0.1, 0.3): sticks below μN, slides at μN",
            "F below μN: no slide, friction = F; beyond: friction μN and the slide of the net pull, (2μN/TM)(t − T/2)³/6",
        ),
        "plies/incline" => (
            "a two-ply stack on an incline 1 % below and above the critical slope, μ_tool < μ_ply and μ_ply < μ_tool",
            "the friction angle atan(min μ); the stack (or the top ply alone) slides ½g(sin α − μ cos α)t²",
        ),
        "plies/hemisphere-friction" => (
            "two-ply hemisphere [0/90 + ±45] against μ_ply = 0, 0.2, 0.5, 1 (a table), and a four-ply [0/45/90/−45] run",
            "runs complete; the top ply's slip at μ_ply = 1 below that at 0; run times against one ply (a note)",
        ),
        "plies/hemisphere-frictionless" => (
            "two-ply hemisphere [0/90 + ±45] at μ_ply = 0: each ply's shear against that ply formed alone on a mould offset by the other ply's thickness; the same for two equal 0/90 plies",
            "the single-ply runs, element by element (same mesh), yarn bending on in all, the top ply's offset punch frictionless: RMS of the shear difference ≤ 0.5° (the issue's bound), at the end; for the equal plies at the last frame both single runs repeat themselves to 0.05°; per frame in a note, on the punch's dome and off it, beside each single run against itself on a punch 1 µm larger (the noise floor)",
        ),
        "plies/held-frictionless" => (
            "deep drawing (punch, die, fixed holder) of two plies [0/90 + ±45] at μ_ply = 0, both held by tools everywhere: each ply's shear against that ply drawn alone on the tools offset by the other ply's thickness",
            "the single-ply runs, element by element (same mesh, stroke, mass scaling), the offset tools frictionless: RMS of the shear difference ≤ 0.5° (the issue's bound); per frame in a note, in the die's opening and on the flange, beside each single run against itself on a punch 1 µm larger (the noise floor)",
        ),
        "plies/hemisphere-four" => (
            "four plies [0/45/90/−45] formed together on the hemisphere, every ply at one element size, and the bottom ply alone, on 2 threads",
            "the plies' distance from the positions: overlap ≤ 1 % of the thickness; no capped ply solve; full: wall time ≤ 5× one ply's",
        ),
        "plies/pressed-stack" => (
            "two plies [0/90 + ±45] deep drawn under the shipped force-driven blank holder (μ_ply = 0.2)",
            "the run reaches its end time (quick: the first 0.1 s, the holder's ramp and hold; full: the stroke); the plies' distance from the positions: overlap ≤ 1 % of the thickness; the holder's contact carries its force after the ramp",
        ),
        "plies/hemisphere-overlap" => (
            "two plies (0/90 under ±45, μ_ply = 0.2) formed together on the hemisphere: no interpenetration",
            "the plies' distance computed from the positions: largest overlap ≤ 1 % of the ply thickness",
        ),
        "kinematics/polar-decomposition" => (
            "F = R·U on sampled deformation gradients: R orthogonal, U symmetric positive, their product F",
            "exact constructions and nalgebra's SVD (within its own measured error)",
        ),
        "kinematics/rigid-rotation" => (
            "objectivity: F = Q·E for random rotations Q gives the same U and strain increment as E",
            "the unrotated case (U − I and Δε̄ unchanged by Q)",
        ),
        "kinematics/pure-shear" => (
            "shear angle and yarn stretches of pure shear (trellising)",
            "the prescribed shear angle; unit yarn stretch",
        ),
        "kinematics/uniaxial-stretch" => (
            "stretch, logarithmic strain and fibre stretch under uniaxial stretch",
            "closed forms (λ, ln λ)",
        ),
        "kinematics/strain-increment-order" => (
            "the midpoint rotated strain increment converges at second order in the step",
            "the exact logarithmic strain of the path; observed order",
        ),
        "constitutive/presets" => (
            "the two material presets' parameters (E_f, E_m, ρ, Prony terms)",
            "the paper's Table 1 as transcribed in the SPEC",
        ),
        "constitutive/fibre-closed-form" => (
            "the crimped fibre law τ = E_f·(ε − ε_sh(1 − e^(−ε/ε_sh))) over the crimp range and beyond",
            "the closed form from the SPEC's raw parameters",
        ),
        "constitutive/fibre-derivatives" => (
            "the fibre law's energy and tangent are its integral and derivative",
            "central finite differences",
        ),
        "constitutive/fibre-limits" => (
            "the fibre law's limits: the crimp (small strain), the straight yarn (large strain), compression",
            "the closed form's asymptotes E_f·ε²/(2ε_sh) and E_f·(ε − ε_sh)",
        ),
        "constitutive/prony-step-relaxation" => (
            "the Prony resin's relaxation after a strain step, at several step sizes",
            "the analytic hereditary integral",
        ),
        "constitutive/prony-ramp" => (
            "the Prony resin under a constant strain rate, at several step sizes",
            "the analytic hereditary integral of the ramp",
        ),
        "constitutive/resin-moduli" => (
            "the resin's shear moduli: instantaneous, relaxed and the algorithmic modulus at both step limits",
            "G₀ = E/(2(1 + ν)), G∞ = G₀(1 − Σg)",
        ),
        "constitutive/thickness-stretch" => (
            "the thickness stretch λ₃ of the plane-stress resin for given area changes J",
            "its closed form",
        ),
        "explicit/picture-frame" => (
            "a glass square sheared to 60° by a pin-jointed frame: uniform shear and the frame force",
            "the frame's kinematics and the derivative of the resin's energy",
        ),
        "explicit/bias-extension" => (
            "the bias-extension test to 34° of shear: the three shear zones",
            "ideal pin-jointed kinematics, γ_A = 90° − 2·acos((D + u)/(√2·D))",
        ),
        "explicit/uniaxial-tension-warp" => (
            "the end force of a strip stretched along its warp to λ = 1.03",
            "W·(t_f·τ_f(ln λ) + h_m·E_m·ln λ)/λ with the crimped law",
        ),
        "explicit/free-oscillation-energy" => (
            "energy conservation of an undamped free blank over 10⁵ steps",
            "the initial energy",
        ),
        "explicit/determinism" => (
            "the same run on 1 and 2 threads ends bit for bit the same",
            "the one-thread run",
        ),
        "contact/incline" => (
            "a blank sliding or sticking on a tilted plane with Coulomb friction",
            "a = g(sin α − μ cos α); rest when tan α ≤ μ",
        ),
        "contact/capstan" => (
            "a strip pulled round a fixed cylinder: the pulled end's force",
            "the capstan equation T₂ = T₁·e^(μθ)",
        ),
        "contact/no-penetration" => (
            "no node inside a tool, and the force balance at rest, for each tool kind",
            "zero gap and the applied loads",
        ),
        "contact/pinching" => (
            "a strip pinched between die and force-driven holder, pulled: the sliding force",
            "2μF, the friction of both tools",
        ),
        "fishnet/chebyshev-sphere" => (
            "the kinematic net on a sphere: diagonal shear profile and order of convergence",
            "the analytic Chebyshev net, (zγ′)′ = cos γ, integrated by RK4",
        ),
        "fishnet/hemisphere-mechanical-vs-kinematic" => (
            "a forming run of hemisphere-conform.toml against the kinematic net where the fabric lies on the mould",
            "drape's kinematic net (drape compare SCENE)",
        ),
        "implicit/incline" => (
            "contact/incline run by the implicit driver",
            "as contact/incline",
        ),
        "implicit/capstan" => (
            "contact/capstan run by the implicit driver",
            "as contact/capstan",
        ),
        "implicit/no-penetration" => (
            "contact/no-penetration run by the implicit driver",
            "as contact/no-penetration",
        ),
        "implicit/pinching" => (
            "contact/pinching run by the implicit driver",
            "as contact/pinching",
        ),
        "implicit/picture-frame" => (
            "explicit/picture-frame run by the implicit driver",
            "as explicit/picture-frame",
        ),
        "implicit/bias-extension" => (
            "explicit/bias-extension run by the implicit driver",
            "as explicit/bias-extension",
        ),
        "implicit/viscoelastic-rate" => (
            "the carbon resin's rate effect: a picture frame to 10° in 1 s and in 100 s",
            "linear viscoelasticity along the frame's path (hereditary integral)",
        ),
        "implicit/determinism" => (
            "the implicit hemisphere on 1 and 2 threads: positions and solver path bit for bit",
            "the one-thread run",
        ),
        "implicit/hemisphere-agreement" => (
            "the shipped 40 × 40 hemispheres (physical mass, bending) by both drivers",
            "the explicit run: max shear and profile within 0.5°, draw-in within 0.5 mm",
        ),
        "implicit/hemisphere-agreement-coarse" => (
            "the same agreement on a 10 × 10 blank, both orientations",
            "the explicit run, same tolerances",
        ),
        "implicit/active-set-incline" => (
            "contact/incline run by the implicit driver with the active-set contact solver",
            "as contact/incline",
        ),
        "implicit/active-set-capstan" => (
            "contact/capstan run by the implicit driver with the active-set contact solver",
            "as contact/capstan",
        ),
        "implicit/active-set-no-penetration" => (
            "contact/no-penetration run by the implicit driver with the active-set contact solver",
            "as contact/no-penetration",
        ),
        "implicit/active-set-pinching" => (
            "contact/pinching run by the implicit driver with the active-set contact solver",
            "as contact/pinching",
        ),
        "implicit/active-set-determinism" => (
            "implicit/determinism with the active-set contact solver",
            "the one-thread run",
        ),
        "implicit/active-set-hemisphere-agreement-coarse" => (
            "implicit/hemisphere-agreement-coarse with the active-set contact solver",
            "the explicit run, same tolerances",
        ),
        "implicit/active-set-hemisphere-agreement" => (
            "implicit/hemisphere-agreement with the active-set contact solver",
            "the explicit run, same tolerances",
        ),
        "implicit/ring-clamp" => (
            "the shipped hemisphere-ring at 20 × 20 by the implicit driver with each contact solver: both complete; forming reported",
            "the run's health: completion, energy balance, at rest at the end",
        ),
        "implicit/holder-force-doubled" => (
            "the ±45 deep drawing at 20 × 20 under twice its holder force by the implicit driver with each contact solver: both complete; forming reported",
            "the run's health: completion, energy balance, at rest at the end",
        ),
        "implicit/hemisphere-shipped" => (
            "the shipped mass-scaled hemispheres by both drivers: same added mass, both complete; differences reported",
            "the explicit run (reported, not checked)",
        ),
        "scenes/deep-drawing-quick" => (
            "both deep-drawing orientations at 20 × 20 quads: the CI's guard on the deep drawing",
            "the run's health: completion and energy balance",
        ),
        "scenes/deep-drawing-stroke" => (
            "the full deep-drawing stroke at three meshes, quads and triangles",
            "energy balance, mesh agreement and a taut-yarn draw-in estimate",
        ),
        "scenes/deep-drawing-sensitivity" => (
            "the ±45 draw-ins against the holder force and the tool radii, one change at a time",
            "the shipped scene's run (trends reported)",
        ),
        "scenes/tray" => (
            "the open CAD tray mould on the defaults: no fold, conforms to the mould, agrees with the net",
            "the fold check, the mould surface (one ply thickness) and the kinematic net (2° RMS)",
        ),
        "bending/rolled-cylinder" => (
            "a strip rolled onto a cylinder: its bending energy",
            "E = B·L·W/(2R²)",
        ),
        "bending/peirce-cantilever-quick" => (
            "Peirce's cantilever (a strip overhanging under its own weight), coarse",
            "the heavy elastica, solved by shooting, and Peirce's formula",
        ),
        "bending/peirce-cantilever" => (
            "Peirce's cantilever at the full set of overhangs and meshes",
            "the heavy elastica, solved by shooting, and Peirce's formula",
        ),
        "locking/picture-frame" => (
            "the picture frame with a shear-locking law: the added frame force from 20° on",
            "the law's own picture-frame curve",
        ),
        "wrinkling/strip-on-foundation-quick" => (
            "a strip on an elastic foundation compressed until it wrinkles: wavelength, coarse",
            "λ_c = 2π·(B/k)^(1/4) (Hetényi; Timoshenko & Gere)",
        ),
        "wrinkling/strip-on-foundation" => (
            "the wrinkle wavelength converging with the mesh, with and without bending",
            "λ_c = 2π·(B/k)^(1/4); without bending the mesh's 2h",
        ),
        "paper/hemisphere-table2" => (
            "the hemisphere laying-up's maximum shear at μ = 0 … 0.5, 0/90 and ±45",
            "El Hami et al. 2009, Table 2 (experiment and the paper's simulation)",
        ),
        "paper/deep-drawing-table4" => (
            "the deep drawing's draw-ins DX, DY, DD at μ = 0.01 … 0.4",
            "El Hami et al. 2009, Table 4",
        ),
        "paper/hemisphere-holding" => (
            "point springs, edge springs and a blank-holder ring: the maximum shear and where",
            "each other; the ring's convergence with the mesh",
        ),
        "paper/mesh-convergence" => (
            "the hemisphere on meshes refined by 2: observed order and Richardson extrapolation",
            "the finest meshes' extrapolation",
        ),
        "pressure/strip-over-gap" => (
            "a strip clamped over a gap and inflated by a follower pressure",
            "a circular arc with T = p·R (hoop formula)",
        ),
        "pressure/strip-over-gap-implicit" => (
            "pressure/strip-over-gap run by the implicit driver",
            "as pressure/strip-over-gap",
        ),
        "cao2008/picture-frame" => (
            "the shear law `drape fit` fits to 7 labs' normalised picture-frame curves of one plain weave, to 40°",
            "the labs' median and range (min..max) at each angle, Cao et al. 2008 benchmark",
        ),
        "cao2008/bias-extension-inverse" => (
            "the shear law fitted by drape's own bias-extension runs (Levenberg–Marquardt) to 3 labs' 230 × 115 mm curves, to 30° of central shear",
            "the labs' median and range (min..max) ± the curves' reading accuracy, Cao et al. 2008 benchmark",
        ),
        "cao2008/bias-extension-picture-frame-law" => (
            "drape's 230 × 115 mm bias extension run with the picture-frame law: its error against the labs (reported) and the three-zone balance of the same law (checked)",
            "the three-zone balance within 3 %, the grips' balance within 0.1 %; the labs' median for the stated error",
        ),
        "cao2008/bias-extension-three-zone" => (
            "the shear law fitted by the ideal three-zone balance to 3 labs' 230 × 115 mm bias-extension curves, to 30° of central shear; the picture-frame law's prediction reported beside it",
            "the labs' median and range (min..max) at each displacement, Cao et al. 2008 benchmark",
        ),
        _ => return None,
    })
}
