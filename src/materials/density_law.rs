//! Density-elasticity laws: Young's modulus (MPa) from a bone density (g/cm³), power laws
//! by piece, with the published presets.

use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};

/// The density a law takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DensityKind {
    /// QCT-equivalent (mineral) density, the calibration's.
    Qct,
    /// Ash density.
    Ash,
    /// Apparent (wet) density.
    App,
}

impl DensityKind {
    /// The name of the per-element density array written (`rho_qct`, `rho_ash`, `rho_app`).
    pub fn array_name(self) -> &'static str {
        match self {
            DensityKind::Qct => "rho_qct",
            DensityKind::Ash => "rho_ash",
            DensityKind::App => "rho_app",
        }
    }
}

/// One piece of a law, valid from density `from` up to the next piece's `from`:
/// `E = offset + coefficient · ρ^exponent` (MPa, ρ in g/cm³).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LawPiece {
    /// Lower end of the piece's density range (g/cm³); the first piece's is ignored.
    #[serde(default)]
    pub from: f64,
    /// MPa per (g/cm³)^exponent.
    pub coefficient: f64,
    /// The exponent.
    pub exponent: f64,
    /// MPa added (default 0).
    #[serde(default)]
    pub offset: f64,
}

/// A density-elasticity law: pieces by increasing density; E of a density at or below zero
/// is 0 (the recipe's floor then applies).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ModulusLaw {
    /// Its name (a preset's, or `custom`).
    pub name: String,
    /// The density it takes.
    pub density: DensityKind,
    /// The pieces, by increasing `from`.
    pub pieces: Vec<LawPiece>,
    /// The source.
    pub source: &'static str,
}

const fn power(coefficient: f64, exponent: f64) -> LawPiece {
    LawPiece {
        from: 0.0,
        coefficient,
        exponent,
        offset: 0.0,
    }
}

/// A preset: name, density, pieces, source.
type Preset = (&'static str, DensityKind, &'static [LawPiece], &'static str);

impl ModulusLaw {
    /// The presets: name, density, pieces, source (E in MPa, ρ in g/cm³).
    pub const PRESETS: &'static [Preset] = &[
        (
            "morgan-2003-femoral-neck",
            DensityKind::App,
            &[power(6850.0, 1.49)],
            "Morgan, Bayraktar & Keaveny 2003, J Biomech 36:897 (femoral neck); the law of \
             Schileo et al. 2008's femur models",
        ),
        (
            "morgan-2003-vertebra",
            DensityKind::App,
            &[power(4730.0, 1.56)],
            "Morgan, Bayraktar & Keaveny 2003, J Biomech 36:897 (vertebra)",
        ),
        (
            "morgan-2003-proximal-tibia",
            DensityKind::App,
            &[power(15520.0, 1.93)],
            "Morgan, Bayraktar & Keaveny 2003, J Biomech 36:897 (proximal tibia)",
        ),
        (
            "morgan-2003-greater-trochanter",
            DensityKind::App,
            &[power(15010.0, 2.18)],
            "Morgan, Bayraktar & Keaveny 2003, J Biomech 36:897 (greater trochanter)",
        ),
        (
            "morgan-2003-pooled",
            DensityKind::App,
            &[power(8920.0, 1.83)],
            "Morgan, Bayraktar & Keaveny 2003, J Biomech 36:897 (all sites pooled)",
        ),
        (
            "kopperdahl-2002-vertebra",
            DensityKind::Qct,
            &[power(2980.0, 1.05)],
            "Kopperdahl & Keaveny's law for vertebral trabecular bone, E = 2980 rho_QCT^1.05 \
             (rho_QCT the K2HPO4-equivalent density of a calibrated QCT), as the spine FE \
             benchmark of Walle, Matheson & Boyd 2025 (GigaScience) uses it",
        ),
        (
            "keller-1994-femur",
            DensityKind::Ash,
            &[power(10500.0, 2.29)],
            "Keller 1994, J Biomech 27:1159 (femur, ash density)",
        ),
        (
            "keyak-2003",
            DensityKind::Ash,
            &[
                power(33900.0, 2.20),
                LawPiece {
                    from: 0.27,
                    coefficient: 5307.0,
                    exponent: 1.0,
                    offset: 469.0,
                },
                LawPiece {
                    from: 0.6,
                    coefficient: 10200.0,
                    exponent: 2.01,
                    offset: 0.0,
                },
            ],
            "Keyak & Falkinstein 2003, Med Eng Phys 25:781 (after Keller 1994; ash density, \
             three pieces)",
        ),
    ];

    /// The preset `name`, or with `name` = `custom` the user's `pieces` on `density`.
    ///
    /// # Errors
    /// [`Error::Parameter`] for an unknown name, a custom law without density or pieces, a
    /// preset given pieces, pieces not finite, not increasing, or with a negative coefficient.
    pub fn named(name: &str, density: Option<DensityKind>, pieces: &[LawPiece]) -> Result<Self> {
        let bad = |m: String| Err(Error::Parameter(format!("material recipe: modulus: {m}")));
        if name == "custom" {
            let Some(density) = density else {
                return bad("a custom law needs `density` (\"qct\", \"ash\" or \"app\")".into());
            };
            if pieces.is_empty() {
                return bad("a custom law needs `pieces` (coefficient, exponent)".into());
            }
            for (i, p) in pieces.iter().enumerate() {
                let finite = [p.from, p.coefficient, p.exponent, p.offset]
                    .iter()
                    .all(|v| v.is_finite());
                if !finite || p.coefficient < 0.0 || p.exponent < 0.0 || p.exponent > 10.0 {
                    return bad(format!(
                        "piece {} must have finite values, coefficient ≥ 0 and exponent in [0, 10]",
                        i + 1
                    ));
                }
                if i > 0 && p.from <= pieces[i - 1].from {
                    return bad(format!(
                        "piece {} starts at {} g/cm³, not above the previous piece's {}",
                        i + 1,
                        p.from,
                        pieces[i - 1].from
                    ));
                }
            }
            return Ok(ModulusLaw {
                name: "custom".into(),
                density,
                pieces: pieces.to_vec(),
                source: "the recipe's own coefficients",
            });
        }
        let Some((n, d, p, s)) = Self::PRESETS.iter().find(|p| p.0 == name) else {
            let names: Vec<&str> = Self::PRESETS.iter().map(|p| p.0).collect();
            return bad(format!(
                "unknown law {name:?}; use one of {} or \"custom\"",
                names.join(", ")
            ));
        };
        if density.is_some() || !pieces.is_empty() {
            return bad(format!(
                "the preset {name} has its own density and pieces; for your own, set law = \"custom\""
            ));
        }
        Ok(ModulusLaw {
            name: (*n).into(),
            density: *d,
            pieces: p.to_vec(),
            source: s,
        })
    }

    /// E (MPa) at density `rho` (g/cm³): the piece whose range holds `rho`; 0 at or below
    /// zero density.
    #[inline]
    pub fn modulus(&self, rho: f64) -> f64 {
        if rho.is_nan() || rho <= 0.0 {
            return 0.0;
        }
        let mut piece = &self.pieces[0];
        for p in &self.pieces[1..] {
            if rho >= p.from {
                piece = p;
            } else {
                break;
            }
        }
        if piece.exponent == 1.0 {
            piece.offset + piece.coefficient * rho
        } else {
            piece.offset + piece.coefficient * rho.powf(piece.exponent)
        }
    }
}
