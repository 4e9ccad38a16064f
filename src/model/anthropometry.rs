//! Segment inertial parameters from Zatsiorsky–Seluyanov as adjusted by de Leva (1996).
//!
//! Source: de Leva P. (1996) "Adjustments to Zatsiorsky-Seluyanov's segment inertia
//! parameters", J Biomech 29(9):1223–1230, **Table 4** (mean segment lengths of the
//! reference subjects, mass as % of body mass, longitudinal centre-of-mass (CM) position
//! as % of segment length from the listed origin, and radii of gyration as % of segment
//! length about the sagittal, transverse and longitudinal axes). The paper itself was not
//! reachable through the search tools; the numbers were taken from two independent public
//! transcriptions of Table 4 that agree with each other where they overlap:
//! R. Gurchiek's `deleva.m` lookup table ("determined from table 4 in de Leva 1996",
//! top and bottom half) and `GabrielEGC/review-sim-amber-robot/Functions/
//! Zatsiorsky_parameters.m` (male mass %, CM %, and lengths/1741 mm). Reference
//! subjects: male stature 1741 mm, mass 73.0 kg; female 1735 mm, 61.9 kg.
//!
//! # Which radius of gyration
//!
//! de Leva's "sagittal" radius is about the sagittal (antero-posterior) axis and the
//! "transverse" radius about the transverse (medio-lateral) axis: e.g. the male trunk has
//! r_sag = 37.2 % > r_trans = 34.7 % because the trunk is wider than it is deep, the hand
//! (wide medio-laterally) r_sag > r_trans, the head (deeper than wide) r_sag < r_trans;
//! Gurchiek reaches the same reading. Rotation **in** the sagittal plane is about the
//! medio-lateral axis, so [`de_leva_planar`] uses the **transverse** column
//! ([`RadiusColumn::Transverse`]). [`de_leva_planar_using`] lets the caller pick the
//! other column (the thigh is identical, the shank and foot differ by 2–5 %).
//!
//! # Segment definitions used
//!
//! * thigh: hip joint centre (HJC) → knee joint centre (KJC);
//! * shank: KJC → ankle joint centre (AJC) (Table 4 alternative definition, so that the
//!   planar chain runs joint centre to joint centre);
//! * foot: heel (HEEL) → toe tip (TTIP); **its `com_from_proximal` is measured from the
//!   heel along the heel–toe line**, because de Leva gives no ankle-referenced value; the
//!   foot geometry (ankle relative to heel) belongs to the foot model;
//! * HAT (head, arms, trunk incl. pelvis): lumped rigid body above the hip-joint-centre
//!   midpoint (MIDH); see [`de_leva_hat_parts`] for the assumptions.
//!
//! The planar model's segments and bodies are built from these parameters in
//! [`super::segments`].
use crate::model::error::AnthropometryError;
use serde::{Deserialize, Serialize};

/// Sex of the de Leva reference population.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Sex {
    /// de Leva's male reference population.
    Male,
    /// de Leva's female reference population.
    Female,
}

/// Which de Leva radius-of-gyration column is used for the planar moment of inertia.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RadiusColumn {
    /// About the antero-posterior axis (de Leva "Sag").
    Sagittal,
    /// About the medio-lateral axis (de Leva "Trans"): rotation in the sagittal plane.
    Transverse,
}

/// One row of de Leva (1996) Table 4 (one sex).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DeLevaRow {
    /// Segment name.
    pub segment: &'static str,
    /// Landmark from which the CM position is measured (de Leva's "origin").
    pub origin: &'static str,
    /// Other end-point.
    pub other: &'static str,
    /// Mean segment length of the reference subject [mm].
    pub length_mm: f64,
    /// Segment mass [% of body mass].
    pub mass_pct: f64,
    /// Longitudinal CM position [% of length from `origin`].
    pub com_pct: f64,
    /// Radius of gyration about the sagittal (AP) axis [% of length].
    pub r_sag_pct: f64,
    /// Radius of gyration about the transverse (ML) axis [% of length].
    pub r_trans_pct: f64,
    /// Radius of gyration about the longitudinal axis [% of length].
    pub r_long_pct: f64,
}

impl DeLevaRow {
    fn radius_pct(&self, col: RadiusColumn) -> f64 {
        match col {
            RadiusColumn::Sagittal => self.r_sag_pct,
            RadiusColumn::Transverse => self.r_trans_pct,
        }
    }
}

/// de Leva (1996) Table 4 for one sex (the rows this crate needs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DeLevaTable {
    /// Reference stature [mm].
    pub stature_mm: f64,
    /// Reference body mass [kg].
    pub body_mass_kg: f64,
    /// Head + neck, vertex (VERT) → C7 (Table 4 alternative definition; same mass and
    /// CM point as the VERT → mid-gonion row).
    pub head: DeLevaRow,
    /// Upper trunk, suprasternale (SUPR) → xiphoid (XYPH).
    pub upper_trunk: DeLevaRow,
    /// Middle trunk, XYPH → omphalion (OMPH).
    pub middle_trunk: DeLevaRow,
    /// Lower trunk (incl. pelvis), OMPH → MIDH.
    pub lower_trunk: DeLevaRow,
    /// Upper arm, shoulder joint centre (SJC) → elbow joint centre (EJC).
    pub upper_arm: DeLevaRow,
    /// Forearm, EJC → wrist joint centre (WJC).
    pub forearm: DeLevaRow,
    /// Hand, WJC → 3rd metacarpale (MET3).
    pub hand: DeLevaRow,
    /// Thigh, HJC → KJC.
    pub thigh: DeLevaRow,
    /// Shank KJC → AJC (alternative definition).
    pub shank: DeLevaRow,
    /// Foot, HEEL → toe tip (TTIP).
    pub foot: DeLevaRow,
    /// Length of the alternative trunk C7 → MIDH [mm] (places C7 above MIDH).
    pub trunk_c7_midh_mm: f64,
    /// Length of the alternative trunk mid-shoulder-joint-centres → MIDH [mm] (places the
    /// shoulder joint centres above MIDH).
    pub trunk_shoulder_midh_mm: f64,
}

#[allow(clippy::too_many_arguments)]
const fn row(
    segment: &'static str,
    origin: &'static str,
    other: &'static str,
    length_mm: f64,
    mass_pct: f64,
    com_pct: f64,
    r_sag_pct: f64,
    r_trans_pct: f64,
    r_long_pct: f64,
) -> DeLevaRow {
    DeLevaRow {
        segment,
        origin,
        other,
        length_mm,
        mass_pct,
        com_pct,
        r_sag_pct,
        r_trans_pct,
        r_long_pct,
    }
}

/// de Leva (1996) Table 4, males (reference: 1741 mm, 73.0 kg).
pub const DE_LEVA_MALE: DeLevaTable = DeLevaTable {
    stature_mm: 1741.0,
    body_mass_kg: 73.0,
    head: row("head", "VERT", "C7", 242.9, 6.94, 50.02, 30.3, 31.5, 26.1),
    upper_trunk: row(
        "upper_trunk",
        "SUPR",
        "XYPH",
        170.7,
        15.96,
        29.99,
        71.6,
        45.4,
        65.9,
    ),
    middle_trunk: row(
        "middle_trunk",
        "XYPH",
        "OMPH",
        215.5,
        16.33,
        45.02,
        48.2,
        38.3,
        46.8,
    ),
    lower_trunk: row(
        "lower_trunk",
        "OMPH",
        "MIDH",
        145.7,
        11.17,
        61.15,
        61.5,
        55.1,
        58.7,
    ),
    upper_arm: row(
        "upper_arm",
        "SJC",
        "EJC",
        281.7,
        2.71,
        57.72,
        28.5,
        26.9,
        15.8,
    ),
    forearm: row(
        "forearm", "EJC", "WJC", 268.9, 1.62, 45.74, 27.6, 26.5, 12.1,
    ),
    hand: row("hand", "WJC", "MET3", 86.2, 0.61, 79.00, 62.8, 51.3, 40.1),
    thigh: row("thigh", "HJC", "KJC", 422.2, 14.16, 40.95, 32.9, 32.9, 14.9),
    shank: row("shank", "KJC", "AJC", 440.3, 4.33, 43.95, 25.1, 24.6, 10.2),
    foot: row("foot", "HEEL", "TTIP", 258.1, 1.37, 44.15, 25.7, 24.5, 12.4),
    trunk_c7_midh_mm: 603.3,
    trunk_shoulder_midh_mm: 515.5,
};

/// de Leva (1996) Table 4, females (reference: 1735 mm, 61.9 kg). The published female
/// mass percentages sum to 99.99 %; [`de_leva_planar`] renormalises them (documented).
pub const DE_LEVA_FEMALE: DeLevaTable = DeLevaTable {
    stature_mm: 1735.0,
    body_mass_kg: 61.9,
    head: row("head", "VERT", "C7", 243.7, 6.68, 48.41, 27.1, 29.5, 26.1),
    upper_trunk: row(
        "upper_trunk",
        "SUPR",
        "XYPH",
        142.5,
        15.45,
        20.77,
        74.6,
        50.2,
        71.8,
    ),
    middle_trunk: row(
        "middle_trunk",
        "XYPH",
        "OMPH",
        205.3,
        14.65,
        45.12,
        43.3,
        35.4,
        41.5,
    ),
    lower_trunk: row(
        "lower_trunk",
        "OMPH",
        "MIDH",
        181.5,
        12.47,
        49.20,
        43.3,
        40.2,
        44.4,
    ),
    upper_arm: row(
        "upper_arm",
        "SJC",
        "EJC",
        275.1,
        2.55,
        57.54,
        27.8,
        26.0,
        14.8,
    ),
    forearm: row("forearm", "EJC", "WJC", 264.3, 1.38, 45.59, 26.1, 25.7, 9.4),
    hand: row("hand", "WJC", "MET3", 78.0, 0.56, 74.74, 53.1, 45.4, 33.5),
    thigh: row("thigh", "HJC", "KJC", 368.5, 14.78, 36.12, 36.9, 36.4, 16.2),
    shank: row("shank", "KJC", "AJC", 438.6, 4.81, 43.52, 26.7, 26.3, 9.2),
    foot: row("foot", "HEEL", "TTIP", 228.3, 1.29, 40.14, 29.9, 27.9, 13.9),
    trunk_c7_midh_mm: 614.8,
    trunk_shoulder_midh_mm: 497.9,
};

impl DeLevaTable {
    /// Table for `sex`.
    pub fn for_sex(sex: Sex) -> &'static DeLevaTable {
        match sex {
            Sex::Male => &DE_LEVA_MALE,
            Sex::Female => &DE_LEVA_FEMALE,
        }
    }

    /// Sum of the mass percentages of the 16 segments (head, 3 trunk parts, 2×3 arm,
    /// 2×3 leg): 100.00 (male), 99.99 (female).
    pub fn mass_pct_sum(&self) -> f64 {
        self.head.mass_pct
            + self.upper_trunk.mass_pct
            + self.middle_trunk.mass_pct
            + self.lower_trunk.mass_pct
            + 2.0 * (self.upper_arm.mass_pct + self.forearm.mass_pct + self.hand.mass_pct)
            + 2.0 * (self.thigh.mass_pct + self.shank.mass_pct + self.foot.mass_pct)
    }
}

/// Inertial parameters of one planar segment.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SegmentParams {
    /// Segment name.
    pub name: String,
    /// [kg]
    pub mass: f64,
    /// Proximal → distal joint [m] (foot: heel → toe tip; HAT: MIDH → vertex).
    pub length: f64,
    /// CM distance from the proximal end along the segment [m] (foot: from the heel;
    /// HAT: above MIDH).
    pub com_from_proximal: f64,
    /// Moment of inertia about the CM for rotation in the sagittal plane [kg·m²].
    pub inertia_com: f64,
}

/// The seven planar segments: HAT + 2 × (thigh, shank, foot); both legs share the
/// parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlanarBodySegments {
    /// Head + arms + trunk + pelvis, COM measured from the hip-joint-centre midpoint upward.
    pub hat: SegmentParams,
    /// Thigh, HJC → KJC (each leg).
    pub thigh: SegmentParams,
    /// Shank, KJC → AJC (each leg).
    pub shank: SegmentParams,
    /// Foot, HEEL → TTIP (each leg); CM measured from the heel.
    pub foot: SegmentParams,
    /// [kg]
    pub total_mass: f64,
    /// [m]
    pub height: f64,
}

impl PlanarBodySegments {
    /// HAT + 2 × (thigh + shank + foot) [kg].
    pub fn segment_mass_sum(&self) -> f64 {
        self.hat.mass + 2.0 * (self.thigh.mass + self.shank.mass + self.foot.mass)
    }
}

/// One body part lumped into the HAT, placed on the vertical line through MIDH.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HatPart {
    /// Part name.
    pub name: String,
    /// [kg] (for arms: both sides together)
    pub mass: f64,
    /// CM height above MIDH [m] (negative = below).
    pub com_height: f64,
    /// Own moment of inertia about its CM, sagittal-plane rotation [kg·m²] (both sides).
    pub inertia_com: f64,
}

fn check_inputs(mass_kg: f64, height_m: f64) -> Result<(), AnthropometryError> {
    if !(mass_kg.is_finite() && mass_kg > 0.0) {
        return Err(AnthropometryError::Mass { mass_kg });
    }
    if !(height_m.is_finite() && height_m > 0.0) {
        return Err(AnthropometryError::Height { height_m });
    }
    Ok(())
}

/// The body parts lumped into the HAT, standing upright with the arms hanging.
///
/// Assumptions (all lengths de Leva's reference lengths × height/stature_ref):
/// * every part's CM lies on one vertical line through MIDH (no antero-posterior offsets:
///   spinal curvature, the posterior C7 and the arms' slight forward hang are ignored);
/// * trunk: lower (OMPH→MIDH), middle (XYPH→OMPH) and upper (SUPR→XYPH) trunk stacked
///   from MIDH upward (their lengths add up to the SUPR→MIDH trunk length, 531.9 mm male);
///   the lower trunk contains the pelvis;
/// * head + neck: vertex at `trunk_c7_midh_mm + head(VERT→C7)` above MIDH, CM 50.02 %
///   (male) below the vertex. Stacking the two segment lengths vertically slightly
///   overstates the vertex height because the neck is inclined;
/// * arms hanging straight down: shoulder joint centres at `trunk_shoulder_midh_mm`
///   above MIDH, then upper arm, forearm and hand;
/// * each part's own inertia uses the chosen radius column; the HAT inertia about its CM
///   follows from the parallel-axis theorem (see [`de_leva_planar_using`]).
pub fn de_leva_hat_parts(
    mass_kg: f64,
    height_m: f64,
    sex: Sex,
    column: RadiusColumn,
) -> Result<Vec<HatPart>, AnthropometryError> {
    check_inputs(mass_kg, height_m)?;
    let t = DeLevaTable::for_sex(sex);
    let scale = height_m / (t.stature_mm * 1e-3); // height ratio
    let mass_norm = mass_kg / t.mass_pct_sum(); // kg per table-%
    let len = |r: &DeLevaRow| r.length_mm * 1e-3 * scale;
    let own = |r: &DeLevaRow, count: f64| {
        let m = count * r.mass_pct * mass_norm;
        let rg = r.radius_pct(column) * 1e-2 * len(r);
        (m, m * rg * rg)
    };
    let mut parts = Vec::with_capacity(7);
    let mut push = |name: &str, r: &DeLevaRow, count: f64, h: f64| {
        let (m, i) = own(r, count);
        parts.push(HatPart {
            name: name.to_string(),
            mass: m,
            com_height: h,
            inertia_com: i,
        });
    };
    // Trunk parts: CM % is measured from the cranial end (origin).
    let (lt, mt, ut) = (&t.lower_trunk, &t.middle_trunk, &t.upper_trunk);
    push("lower_trunk", lt, 1.0, len(lt) * (1.0 - lt.com_pct * 1e-2));
    push(
        "middle_trunk",
        mt,
        1.0,
        len(lt) + len(mt) * (1.0 - mt.com_pct * 1e-2),
    );
    push(
        "upper_trunk",
        ut,
        1.0,
        len(lt) + len(mt) + len(ut) * (1.0 - ut.com_pct * 1e-2),
    );
    let c7 = t.trunk_c7_midh_mm * 1e-3 * scale;
    push(
        "head",
        &t.head,
        1.0,
        c7 + len(&t.head) * (1.0 - t.head.com_pct * 1e-2),
    );
    let sjc = t.trunk_shoulder_midh_mm * 1e-3 * scale;
    let (ua, fa, ha) = (&t.upper_arm, &t.forearm, &t.hand);
    push("upper_arms", ua, 2.0, sjc - len(ua) * ua.com_pct * 1e-2);
    push(
        "forearms",
        fa,
        2.0,
        sjc - len(ua) - len(fa) * fa.com_pct * 1e-2,
    );
    push(
        "hands",
        ha,
        2.0,
        sjc - len(ua) - len(fa) - len(ha) * ha.com_pct * 1e-2,
    );
    Ok(parts)
}

/// Planar segment parameters for a subject of `mass_kg`, `height_m`, using de Leva's
/// transverse (medio-lateral axis) radii — see the module docs.
pub fn de_leva_planar(
    mass_kg: f64,
    height_m: f64,
    sex: Sex,
) -> Result<PlanarBodySegments, AnthropometryError> {
    de_leva_planar_using(mass_kg, height_m, sex, RadiusColumn::Transverse)
}

/// As [`de_leva_planar`] with an explicit radius-of-gyration column.
///
/// * masses: body mass × Table 4 % / (sum of the 16 segment %) — the division only
///   matters for females (99.99 %), and makes the 7 planar segments sum to the body mass;
/// * lengths: Table 4 reference length × height / reference stature;
/// * CM: Table 4 % × length from the proximal end (thigh HJC, shank KJC, foot HEEL);
/// * inertia: mass × (radius % × length)²;
/// * HAT: parts of [`de_leva_hat_parts`]; mass = Σ m_i, CM height h = Σ m_i h_i / m,
///   I = Σ (I_i + m_i (h_i − h)²); length = vertex height above MIDH.
pub fn de_leva_planar_using(
    mass_kg: f64,
    height_m: f64,
    sex: Sex,
    column: RadiusColumn,
) -> Result<PlanarBodySegments, AnthropometryError> {
    check_inputs(mass_kg, height_m)?;
    let t = DeLevaTable::for_sex(sex);
    let scale = height_m / (t.stature_mm * 1e-3);
    let mass_norm = mass_kg / t.mass_pct_sum();
    let seg = |r: &DeLevaRow| {
        let length = r.length_mm * 1e-3 * scale;
        let mass = r.mass_pct * mass_norm;
        let rg = r.radius_pct(column) * 1e-2 * length;
        SegmentParams {
            name: r.segment.to_string(),
            mass,
            length,
            com_from_proximal: r.com_pct * 1e-2 * length,
            inertia_com: mass * rg * rg,
        }
    };
    let parts = de_leva_hat_parts(mass_kg, height_m, sex, column)?;
    let m_hat: f64 = parts.iter().map(|p| p.mass).sum();
    let h_hat = parts.iter().map(|p| p.mass * p.com_height).sum::<f64>() / m_hat;
    let i_hat: f64 = parts
        .iter()
        .map(|p| p.inertia_com + p.mass * (p.com_height - h_hat).powi(2))
        .sum();
    let hat = SegmentParams {
        name: "hat".to_string(),
        mass: m_hat,
        length: (t.trunk_c7_midh_mm + t.head.length_mm) * 1e-3 * scale,
        com_from_proximal: h_hat,
        inertia_com: i_hat,
    };
    Ok(PlanarBodySegments {
        hat,
        thigh: seg(&t.thigh),
        shank: seg(&t.shank),
        foot: seg(&t.foot),
        total_mass: mass_kg,
        height: height_m,
    })
}
