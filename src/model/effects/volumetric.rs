//! The `volumetric_contact` effect: the volumetric contact law's stiffness, damping and
//! dynamic friction coefficient ([`crate::model::volumetric`]) as parameters of the model,
//! identified by optimal control as Ezati et al. (2020) do.

use super::{Effect, ParamSpec};

/// Frees the stiffness, damping and dynamic friction coefficient of the foot's volumetric
/// primitives. Each named primitive has its own three parameters, shared by the same
/// primitive of both feet (a symmetric subject, as the half-cycle problems with their
/// left↔right periodicity assume). The friction law's static coefficient keeps the foot
/// file's margin μ_s − μ_d above the dynamic one, and its transition velocity stays.
///
/// The parameters enter the volumetric forces of every dynamics evaluation as the
/// generic scalar of the model (`GaitModel::volumetric_forces`), so their sensitivities
/// are exact. The stiffness is in N/mm² (1 N/mm² = 10⁶ N/m², the foot file's unit) so
/// that all three are of order one in θ.
#[derive(Debug, Clone)]
pub struct VolumetricContact {
    primitives: Vec<String>,
    params: Vec<ParamSpec>,
}

/// One primitive's law as the effect starts from: stiffness (N/m²), damping (s/m) and
/// dynamic friction coefficient.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VolumetricStart {
    /// Area stiffness (N/m², as in the foot file).
    pub stiffness: f64,
    /// Damping (s/m).
    pub damping: f64,
    /// Dynamic friction coefficient.
    pub mu_dynamic: f64,
}

impl VolumetricContact {
    /// Bounds of the area stiffness (N/mm²): 0.05 N/mm² sinks a foot about 3 cm under body
    /// weight, 50 N/mm² under 1 mm.
    pub const STIFFNESS_BOUNDS: (f64, f64) = (0.05, 50.0);
    /// Bounds of the damping (s/m; Ezati et al. (2020) identified 0.92).
    pub const DAMPING_BOUNDS: (f64, f64) = (0.0, 5.0);
    /// Bounds of the dynamic friction coefficient.
    pub const MU_BOUNDS: (f64, f64) = (0.05, 1.5);
    /// N/m² per N/mm².
    pub const STIFFNESS_UNIT: f64 = 1e6;

    /// The law of each named primitive (`(name, start)`), each parameter free or not.
    pub fn new(primitives: &[(String, VolumetricStart)], free: [bool; 3]) -> Self {
        let mut params = Vec::new();
        for (name, s) in primitives {
            let base = format!("volumetric_contact.{name}");
            params.push(ParamSpec {
                name: format!("{base}.stiffness"),
                value: s.stiffness / Self::STIFFNESS_UNIT,
                lower: Self::STIFFNESS_BOUNDS.0,
                upper: Self::STIFFNESS_BOUNDS.1,
                unit: "N/mm²".into(),
                free: free[0],
            });
            params.push(ParamSpec {
                name: format!("{base}.damping"),
                value: s.damping,
                lower: Self::DAMPING_BOUNDS.0,
                upper: Self::DAMPING_BOUNDS.1,
                unit: "s/m".into(),
                free: free[1],
            });
            params.push(ParamSpec {
                name: format!("{base}.mu_dynamic"),
                value: s.mu_dynamic,
                lower: Self::MU_BOUNDS.0,
                upper: Self::MU_BOUNDS.1,
                unit: "".into(),
                free: free[2],
            });
        }
        Self {
            primitives: primitives.iter().map(|p| p.0.clone()).collect(),
            params,
        }
    }
}

impl Effect for VolumetricContact {
    fn kind(&self) -> &'static str {
        "volumetric_contact"
    }
    fn parameters(&self) -> &[ParamSpec] {
        &self.params
    }
    fn volumetric_primitives(&self) -> &[String] {
        &self.primitives
    }
}
