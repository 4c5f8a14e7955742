//! A fabric material: fibres, resin, thickness, fibre volume fraction,
//! density; its validation and the paper's presets.

use serde::{Deserialize, Serialize};

use crate::{FibreLaw, PronyTerm, ResinLaw};

/// An invalid material parameter: which field, its value, what is allowed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("invalid material field `{field}` = {value}: expected {expected}")]
pub struct MaterialError {
    /// Dotted path of the field, e.g. `resin.prony[2].tau`.
    pub field: String,
    /// The offending value (for a sum, the sum).
    pub value: f64,
    /// What the field accepts.
    pub expected: &'static str,
}

impl MaterialError {
    pub(crate) fn check(
        path: &str,
        field: &str,
        value: f64,
        ok: bool,
        expected: &'static str,
    ) -> Result<(), Self> {
        // NaN fails every comparison, so `ok` is false for it as well.
        if ok && value.is_finite() {
            Ok(())
        } else {
            Err(Self {
                field: if path.is_empty() {
                    field.to_owned()
                } else {
                    format!("{path}.{field}")
                },
                value,
                expected,
            })
        }
    }

    pub(crate) fn check_positive(path: &str, field: &str, value: f64) -> Result<(), Self> {
        Self::check(path, field, value, value > 0.0, "a positive finite number")
    }
}

/// A woven fabric: two identical yarn families (warp and weft) in a resin.
///
/// The fibres take V_f of the volume, V_f/2 per family; the resin membrane
/// has thickness h_m = (1 − V_f)·h (SPEC §2).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    /// A name for reports.
    pub name: String,
    /// The yarns' law (both families).
    pub fibre: FibreLaw,
    /// The resin's law.
    pub resin: ResinLaw,
    /// h, the fabric thickness (mm).
    pub thickness: f64,
    /// V_f, the fibre volume fraction, in (0, 1).
    pub fibre_volume_fraction: f64,
    /// ρ, the fabric's density (t/mm³).
    pub density: f64,
    /// Bending rigidity of [warp, weft] (N·mm: bending moment per unit
    /// width per unit curvature, B = w·c³ from a cantilever test's bending
    /// length c and areal weight w). A scene bends the yarns with it by
    /// default (where its mesh follows the yarns); without it a scene runs
    /// a membrane that can fold at no cost, and says so.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bending_rigidity: Option<[f64; 2]>,
}

/// Assumed bending rigidity of `glass-serge-4x3` (N·mm), see [`Material::preset`].
const GLASS_BENDING: f64 = 1.3e-9 * 0.57 * 9810.0 * 40.0 * 40.0 * 40.0;
/// Assumed bending rigidity of `carbon-prepreg-2x2` (N·mm), see [`Material::preset`].
const CARBON_BENDING: f64 = 1.5e-9 * 0.3 * 9810.0 * 80.0 * 80.0 * 80.0;

/// Assumed bending rigidity of `twintex-plain` (N·mm), see [`Material::preset`]:
/// B = w·c³, w = 743 g/m²·g, c = 50 mm.
const TWINTEX_BENDING: f64 = 743e-6 * 9.81e-3 * 50.0 * 50.0 * 50.0;
/// `twintex-plain`'s in-plane shear law (MPa, γ in rad): the joint fit of
/// the Cao et al. 2008 labs' normalised picture-frame curves to 40°
/// (`drape fit picture-frame tests/data/cao2008/picture_frame_plain_normalised.csv
/// --force normalised --max-angle 40 --material twintex-plain`; a test of
/// `drape fit` checks that it still gives these numbers).
const TWINTEX_SHEAR: [f64; 3] = [
    0.07664988034294244,
    -0.12165889308025254,
    0.3107451018711586,
];

/// σ_b = π²·B/(L²·V_f·h/2), the Euler stress of a yarn segment of length
/// L between interlacings ([`FibreLaw::buckling_stress`]), from a preset's
/// bending rigidity B (N·mm), L (mm), V_f and h (mm).
fn euler_buckling_stress(bending: f64, segment: f64, fibre_volume_fraction: f64, h: f64) -> f64 {
    std::f64::consts::PI.powi(2) * bending / (segment * segment * 0.5 * fibre_volume_fraction * h)
}

/// L of `glass-serge-4x3` (mm): one pitch at the paper's 2.2 yarns/cm.
const GLASS_SEGMENT: f64 = 10.0 / 2.2;
/// L of `carbon-prepreg-2x2` (mm), **\[assumption\]**: a 2×2 twill's yarn
/// interlaces every second crossing, at 5 yarns/cm (a 3K 200 g/m² twill).
const CARBON_SEGMENT: f64 = 2.0 * 10.0 / 5.0;
/// L of `twintex-plain` (mm): one pitch at the benchmark's 1.93 yarns/cm.
const TWINTEX_SEGMENT: f64 = 10.0 / 1.93;

/// The names [`Material::preset`] knows.
pub const PRESET_NAMES: [&str; 3] = ["carbon-prepreg-2x2", "glass-serge-4x3", "twintex-plain"];

impl Material {
    /// A named preset of the paper (SPEC §4):
    ///
    /// - `carbon-prepreg-2x2`, paper Table 1: E_f = 230 GPa, ε_sh = 0.005,
    ///   E_m = 45 MPa, ν_m = 0.45 and the six-term Prony series of the
    ///   table. Not given by the paper and chosen here: h = 0.3 mm (a typical
    ///   2×2 twill carbon prepreg ply), V_f = 0.5, ρ = 1.5e-9 t/mm³
    ///   (1500 kg/m³, carbon/epoxy at V_f = 0.5).
    /// - `glass-serge-4x3`, paper Table 3: E_f = 75 GPa, ε_sh = 0.012,
    ///   E_m = 30 MPa, ν_m = 0.41, h = 0.57 mm, elastic resin. Chosen here:
    ///   V_f = 0.5, ρ = 1.3e-9 t/mm³ (glass fabric with a low resin
    ///   content). Its yarn density, 2.2 yarns/cm, is a property of the mesh
    ///   a user builds, not of the material.
    ///
    /// - `twintex-plain`, the plain-weave commingled glass/polypropylene
    ///   (Twintex) of the woven-fabric benchmark, Cao et al., Composites A
    ///   39 (2008) 1037–1053, Table 1, tested dry at room temperature:
    ///   areal density 743 g/m², h = 1.2 mm (at 4.14 kPa), so
    ///   ρ = 743 g/m²/1.2 mm = 6.19e-10 t/mm³. Its 1.93 yarns/cm (a pitch
    ///   of 5.18 mm) and 4.2 mm yarn width belong to the mesh a user builds
    ///   (they put the geometric jamming angle at acos(4.2/5.18) = 36°; the
    ///   paper sees locking begin near 45°). The paper gives no yarn
    ///   stiffness or bending: **\[assumptions\]** here. Yarns: E_f = 73 GPa
    ///   (E-glass; the polypropylene filaments carry little) over the glass
    ///   cross-section, from Twintex's nominal 60 % glass by weight and a
    ///   glass density of 2.54 g/cm³: 0.6·743 g/m² / 2.54 g/cm³ = 0.176 mm
    ///   of glass in 1.2 mm, V_f = 0.146 (so a family's tensile stiffness
    ///   per unit width is E_f·V_f·h/2 = 6.4 kN/mm); crimp ε_sh = 0.01
    ///   (assumed, a plain weave's typical order). In-plane shear: the
    ///   fitted law of the benchmark's labs (`TWINTEX_SHEAR`), with the
    ///   resin membrane made negligible (E_m = 0.002 MPa, ν_m = 0.3, under
    ///   1 % of the law's initial shear stiffness) since a dry fabric has
    ///   no resin to shear. Bending: B = w·c³ with an assumed bending
    ///   length c = 50 mm (w = 7.29e-6 N/mm², B = 0.91 N·mm), reasoned as
    ///   for the glass serge below (the same areal weight, twice as thick).
    ///
    /// Yarns in compression (beyond the paper, whose yarns buckle at no
    /// cost, c_c = 0): each preset's yarn is an imperfect column between
    /// interlacings ([`FibreLaw::buckling_stress`]), bowed by its own crimp,
    /// whose load tends to the Euler stress σ_b = π²·B/(L²·V_f·h/2) of a
    /// segment of length L with the preset's bending rigidity B:
    /// glass-serge-4x3 L = 4.55 mm (one pitch at 2.2 yarns/cm), σ_b =
    /// 1.56 MPa; carbon-prepreg-2x2 L = 4 mm (assumed, see
    /// `CARBON_SEGMENT`), σ_b = 18.6 MPa; twintex-plain L = 5.18 mm (one
    /// pitch at 1.93 yarns/cm), σ_b = 3.82 MPa. Why: with c_c = 0 a ply
    /// lies on a double-curved tool by shortening its yarns below the
    /// mesh's scale at no cost, where a fabric must shear or wrinkle; a
    /// buckled yarn keeps carrying its Euler load. L is the shortest span
    /// a yarn can buckle over (the crossing yarns pin it), so σ_b is the
    /// most a buckling yarn carries; B is the assumed rigidity below, so
    /// σ_b is as uncertain as B. The paper's own law (c_c = 0) is
    /// [`Self::paper_preset`].
    ///
    /// Confined yarns: the glass and twintex presets carry their L
    /// ([`FibreLaw::segment_length`]), so that between two tools their
    /// column can bow out no further than the free space the tools leave
    /// ([`FibreLaw::confined_stress_and_tangent`]). The carbon prepreg's
    /// does not: its walled tangent at a closed gap, 1/(ε_sh/σ_b + 1/E_f)
    /// = 3.7 GPa, is 1.6 % of its E_f, past [`FibreLaw::KINK_SHARE`], so
    /// confining it would put dashpots on every carbon run's yarns
    /// (ARCHITECTURE.md, "Dashpots on kinked yarns"), a change of the
    /// carbon cases this was not checked against **\[choice\]**.
    ///
    /// Bending rigidities (on by default in a scene, so they shape every
    /// run that does not turn bending off) are **\[assumptions\]**, not
    /// measurements: the paper gives none, and no published bending
    /// rigidity of these two fabrics, or of a comparable woven glass
    /// fabric or uncured woven carbon prepreg, was found in the sources
    /// searched while writing this (the textile and forming literature
    /// reachable from the project; the papers found —
    /// Lammens et al., Textile Res. J. 84(12), 2014, 1307–1314 on the
    /// accuracy of Peirce's test, Yu et al., Composites A 143, 2021,
    /// 106308 on bending and wrinkling — were available as abstracts
    /// only, without their figures). Searched again when bending became the
    /// default (cantilever and ASTM D1388 bending lengths of woven glass
    /// and carbon twill prepreg, bending rigidity per unit width): the
    /// sources reached were the ASTM D1388 scope, Lammens et al.'s values
    /// for a polyimide foil only, and without usable figures Ghafour,
    /// Colmars and Boisse, Front. Mater. 8, 2021, 728485 (inelastic
    /// bending of textile preforms), Broberg et al., Composites B, 2023,
    /// 110763 (moment–curvature from a cantilever) and Liang et al.,
    /// hal-04670774 (curvature in the bending test of reinforcements); so
    /// the values stay assumptions. Each is B = w·c³ (Peirce's cantilever
    /// relation) from the preset's own areal weight w = ρ·h·g and an
    /// assumed bending length c, the same for warp and weft (balanced
    /// weaves): c = 40 mm for the heavy glass serge (w = 7.27e-6 N/mm²,
    /// B = 0.465 N·mm) and c = 80 mm for the uncured carbon prepreg
    /// (w = 4.41e-6 N/mm², B = 2.26 N·mm), the resin's tack making a
    /// prepreg stiffer in bending than its dry fabric. Nothing but that
    /// reasoning supports either length, not even its order of magnitude
    /// (B ∝ c³: c off by 2 puts B off by 8). Replace them by a
    /// cantilever test of the actual material, read with the elastica
    /// rather than Peirce's formula: on a foil of known modulus Lammens et
    /// al. found Peirce's formula 18 % high and the ASTM D1388 procedure
    /// 72 % high (drape's own cantilever case gives the elastica).
    pub fn preset(name: &str) -> Option<Self> {
        match name {
            "carbon-prepreg-2x2" => {
                let taus = [0.01, 0.1, 1.0, 10.0, 100.0, 1000.0];
                let gs = [0.02332, 0.023332, 0.083509, 0.11723, 0.14423, 0.178];
                Some(Self {
                    name: name.to_owned(),
                    fibre: FibreLaw {
                        modulus: 230_000.0,
                        crimp_strain: 0.005,
                        compression_factor: 0.0,
                        buckling_stress: euler_buckling_stress(
                            CARBON_BENDING,
                            CARBON_SEGMENT,
                            0.5,
                            0.3,
                        ),
                        // Not confined: see "Confined yarns" above.
                        segment_length: 0.0,
                    },
                    resin: ResinLaw {
                        young: 45.0,
                        poisson: 0.45,
                        prony: gs
                            .iter()
                            .zip(taus)
                            .map(|(&g, tau)| PronyTerm { g, tau })
                            .collect(),
                        shear_locking: None,
                    },
                    thickness: 0.3,
                    fibre_volume_fraction: 0.5,
                    density: 1.5e-9,
                    bending_rigidity: Some([CARBON_BENDING; 2]),
                })
            }
            "glass-serge-4x3" => Some(Self {
                name: name.to_owned(),
                fibre: FibreLaw {
                    modulus: 75_000.0,
                    crimp_strain: 0.012,
                    compression_factor: 0.0,
                    buckling_stress: euler_buckling_stress(GLASS_BENDING, GLASS_SEGMENT, 0.5, 0.57),
                    segment_length: GLASS_SEGMENT,
                },
                resin: ResinLaw {
                    young: 30.0,
                    poisson: 0.41,
                    prony: Vec::new(),
                    shear_locking: None,
                },
                thickness: 0.57,
                fibre_volume_fraction: 0.5,
                density: 1.3e-9,
                bending_rigidity: Some([GLASS_BENDING; 2]),
            }),
            "twintex-plain" => Some(Self {
                name: name.to_owned(),
                fibre: FibreLaw {
                    modulus: 73_000.0,
                    crimp_strain: 0.01,
                    compression_factor: 0.0,
                    buckling_stress: euler_buckling_stress(
                        TWINTEX_BENDING,
                        TWINTEX_SEGMENT,
                        0.146,
                        1.2,
                    ),
                    segment_length: TWINTEX_SEGMENT,
                },
                resin: ResinLaw {
                    young: 0.002,
                    poisson: 0.3,
                    prony: Vec::new(),
                    shear_locking: Some(crate::ShearLocking {
                        coefficients: TWINTEX_SHEAR.to_vec(),
                        friction: None,
                    }),
                },
                thickness: 1.2,
                fibre_volume_fraction: 0.146,
                // 743 g/m² = 743e-6 t per 1e6 mm².
                density: 743e-12 / 1.2,
                bending_rigidity: Some([TWINTEX_BENDING; 2]),
            }),
            _ => None,
        }
    }

    /// A preset with the paper's yarn (SPEC §4): no compression stiffness
    /// (c_c = 0, σ_b = 0), as the paper's validation runs it; otherwise
    /// [`Self::preset`].
    pub fn paper_preset(name: &str) -> Option<Self> {
        let mut m = Self::preset(name)?;
        m.fibre.buckling_stress = 0.0;
        Some(m)
    }

    /// Checks every parameter, naming the first invalid field.
    pub fn validate(&self) -> Result<(), MaterialError> {
        self.fibre.validate("fibre")?;
        self.resin.validate("resin")?;
        MaterialError::check_positive("", "thickness", self.thickness)?;
        MaterialError::check(
            "",
            "fibre_volume_fraction",
            self.fibre_volume_fraction,
            self.fibre_volume_fraction > 0.0 && self.fibre_volume_fraction < 1.0,
            "a volume fraction in the open interval (0, 1)",
        )?;
        MaterialError::check_positive("", "density", self.density)?;
        if let Some(b) = self.bending_rigidity {
            for (k, value) in b.iter().enumerate() {
                MaterialError::check_positive("", &format!("bending_rigidity[{k}]"), *value)?;
            }
        }
        Ok(())
    }

    /// h_m = (1 − V_f)·h, the resin membrane's thickness.
    #[inline]
    pub fn resin_thickness(&self) -> f64 {
        (1.0 - self.fibre_volume_fraction) * self.thickness
    }

    /// The fibre thickness of one family, V_f/2·h: times a strip width it is
    /// a truss section A₀ (SPEC §2), times an area the fibre volume.
    #[inline]
    pub fn family_thickness(&self) -> f64 {
        0.5 * self.fibre_volume_fraction * self.thickness
    }

    /// ρ·h, the mass per unit area (t/mm²).
    #[inline]
    pub fn areal_density(&self) -> f64 {
        self.density * self.thickness
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_are_valid_and_carry_the_papers_values() {
        for name in PRESET_NAMES {
            let m = Material::preset(name).unwrap();
            m.validate().unwrap();
            assert_eq!(m.name, name);
        }
        let c = Material::preset("carbon-prepreg-2x2").unwrap();
        assert_eq!(c.resin.prony.len(), 6);
        assert_eq!(
            c.resin.prony[5],
            PronyTerm {
                g: 0.178,
                tau: 1000.0
            }
        );
        assert!((c.resin_thickness() - 0.15).abs() < 1e-15);
        let g = Material::preset("glass-serge-4x3").unwrap();
        assert!(!g.resin.is_viscoelastic());
        assert_eq!(g.fibre.crimp_strain, 0.012);
        assert!(Material::preset("kevlar").is_none());
        // The benchmark's table: 743 g/m² at 1.2 mm; 60 % glass by weight
        // at 2.54 g/cm³ is V_f·h of glass.
        let t = Material::preset("twintex-plain").unwrap();
        // t/mm² to kg/m²: ×1e3 kg/t ×1e6 mm²/m² (a factor of 1000 once
        // slipped here, making the specimen 1000× too heavy).
        assert!((t.areal_density() * 1e9 - 0.743).abs() < 1e-12);
        // A dry fabric is lighter than its glass (2540 kg/m³) and heavier
        // than air: 619 kg/m³ here, in t/mm³ ×1e12.
        assert!((t.density * 1e12 - 619.17).abs() < 0.01);
        assert!((t.fibre_volume_fraction * 1.2 - 0.6 * 743.0 / 2.54e6 * 1e3).abs() < 1e-3);
        assert!(t.resin.shear_locking.is_some());
    }

    /// Every preset weighs what a fabric weighs: 50 g/m² to 3 kg/m² (the
    /// lightest veils to the heaviest non-crimp fabrics). A slip of the
    /// t/mm³ unit is a factor of 1000 and lands far outside.
    #[test]
    fn presets_weigh_what_fabrics_weigh() {
        for name in PRESET_NAMES {
            let kg_per_m2 = Material::preset(name).unwrap().areal_density() * 1e9;
            assert!(
                (0.05..3.0).contains(&kg_per_m2),
                "{name}: {kg_per_m2} kg/m²"
            );
        }
    }

    #[test]
    fn paper_presets_keep_the_papers_yarn_and_presets_buckle_at_their_euler_stress() {
        // σ_b = π²·B/(L²·V_f·h/2), worked by hand from the documented
        // numbers (B = w·c³, L from the yarn counts): 4 digits.
        for (name, sigma) in [
            ("glass-serge-4x3", 1.5595),
            ("carbon-prepreg-2x2", 18.590),
            ("twintex-plain", 3.8236),
        ] {
            let preset = Material::preset(name).unwrap();
            let paper = Material::paper_preset(name).unwrap();
            let s = preset.fibre.buckling_stress;
            assert!((s / sigma - 1.0).abs() < 1e-4, "{name}: σ_b {s}");
            // The paper's yarn: nothing in compression, as SPEC §4.
            assert_eq!(paper.fibre.compression_factor, 0.0);
            assert_eq!(paper.fibre.buckling_stress, 0.0);
            assert_eq!(paper.fibre.stress_and_tangent(-0.05), (0.0, 0.0));
            assert_eq!(paper.fibre.energy(-0.05), 0.0);
            // … and otherwise the same material, field by field.
            let mut stripped = preset.clone();
            stripped.fibre.buckling_stress = 0.0;
            assert_eq!(stripped, paper, "{name}");
            // A paper card written out has no buckling key: the text of
            // a card from before the key.
            assert!(!toml::to_string(&paper).unwrap().contains("buckling"));
            paper.validate().unwrap();
        }
        // The tables' literals (SPEC §4), unchanged in the paper's yarn.
        let g = Material::paper_preset("glass-serge-4x3").unwrap().fibre;
        assert_eq!((g.modulus, g.crimp_strain), (75_000.0, 0.012));
        let c = Material::paper_preset("carbon-prepreg-2x2").unwrap().fibre;
        assert_eq!((c.modulus, c.crimp_strain), (230_000.0, 0.005));
        assert!(Material::paper_preset("kevlar").is_none());
    }

    #[test]
    fn toml_round_trip_and_unknown_keys() {
        let c = Material::preset("carbon-prepreg-2x2").unwrap();
        let text = toml::to_string(&c).unwrap();
        let back: Material = toml::from_str(&text).unwrap();
        assert_eq!(back, c);

        let typo = text.replace("crimp_strain", "crimp_stran");
        let err = toml::from_str::<Material>(&typo).unwrap_err().to_string();
        assert!(err.contains("crimp_stran"), "{err}");

        let elastic = r#"
            name = "x"
            thickness = 0.5
            fibre_volume_fraction = 0.4
            density = 1e-9
            fibre = { modulus = 1000.0, crimp_strain = 0.01 }
            resin = { young = 10.0, poisson = 0.3 }
        "#;
        let m: Material = toml::from_str(elastic).unwrap();
        assert_eq!(m.fibre.compression_factor, 0.0);
        assert!(m.resin.prony.is_empty());
    }

    #[test]
    fn invalid_values_name_their_field() {
        let base = Material::preset("carbon-prepreg-2x2").unwrap();
        let field = |m: Material| m.validate().unwrap_err().field;
        assert_eq!(
            field(Material {
                thickness: -0.3,
                ..base.clone()
            }),
            "thickness"
        );
        assert_eq!(
            field(Material {
                fibre_volume_fraction: 1.0,
                ..base.clone()
            }),
            "fibre_volume_fraction"
        );
        assert_eq!(
            field(Material {
                density: 0.0,
                ..base.clone()
            }),
            "density"
        );
        let mut m = base.clone();
        m.resin.young = -45.0;
        assert_eq!(field(m), "resin.young");
        let mut m = base.clone();
        m.fibre.crimp_strain = -0.005;
        let err = m.validate().unwrap_err();
        assert_eq!(err.field, "fibre.crimp_strain");
        assert_eq!(
            err.to_string(),
            "invalid material field `fibre.crimp_strain` = -0.005: expected a crimp strain in [0, 1)"
        );
        let mut m = base;
        m.resin.prony[0].g = 0.6;
        assert_eq!(field(m), "resin.prony");
    }
}
