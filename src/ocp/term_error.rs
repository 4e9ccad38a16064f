//! Why a function of the problem (a [`NodeFunction`](super::NodeFunction), an
//! [`Integrand`](super::Integrand) or a generic function written over model scalars)
//! could not be evaluated at a point.

use crate::integrate::OdeError;
use crate::model::DynamicsError;

/// A boxed error of a function written outside the library, kept as the cause.
pub type ExternalCause = Box<dyn std::error::Error + Send + Sync + 'static>;

/// Failure of one evaluation of a term (its value, Jacobian or weighted Hessian).
///
/// Nothing is allocated on the success path: the variants hold their causes by value, and
/// only the model's own errors and a [`External`](TermError::External) cause carry text. The
/// transcription names the failing term around it
/// ([`TranscriptionError::Term`](super::TranscriptionError::Term)).
#[derive(Debug, thiserror::Error)]
pub enum TermError {
    /// The model's dynamics or impact map cannot be evaluated at the term's arguments (a
    /// mass matrix that is not positive definite, an over-constrained contact set, a
    /// non-finite state).
    #[error(transparent)]
    Dynamics(#[from] DynamicsError),
    /// The phase's right-hand side `ẋ = f(x, u, θ)` failed where a term needed it (the
    /// rate of a sample term whose instant moves with θ).
    #[error(transparent)]
    Ode(#[from] OdeError),
    /// A sample term's shift of its instant, or its gradient in θ, is not finite.
    #[error("{}", shift_message(.shift))]
    NonFiniteShift {
        /// The shift (s) the term's shift function returned.
        shift: f64,
    },
    /// The function provides no weighted Hessian (the default of
    /// [`NodeFunction::weighted_hessian`](super::NodeFunction::weighted_hessian), which is
    /// only asked for where [`has_hessian`](super::NodeFunction::has_hessian) says so).
    #[error("no Hessian provided")]
    NoHessian,
    /// A function written outside the library failed, with its own error (see
    /// [`TermError::external`]).
    #[error(transparent)]
    External(ExternalCause),
}

impl TermError {
    /// A failure of a function written outside the library, from its own error or from a
    /// message (`&str`, `String`).
    pub fn external(cause: impl Into<ExternalCause>) -> Self {
        TermError::External(cause.into())
    }

    /// Whether another point may evaluate where this one failed. Every term failure is
    /// taken as one of the point: the model outside its domain there, a shift that
    /// overflowed, a function that gave up there; a missing Hessian is asked for only of
    /// functions that claim one, so it too is a failure at the point, not of the problem.
    pub fn is_recoverable(&self) -> bool {
        match self {
            TermError::Dynamics(_)
            | TermError::Ode(_)
            | TermError::NonFiniteShift { .. }
            | TermError::NoHessian
            | TermError::External(_) => true,
        }
    }
}

/// The text of [`TermError::NonFiniteShift`]: the shift, or its gradient where the shift
/// itself is finite.
fn shift_message(shift: &f64) -> String {
    if shift.is_finite() {
        format!("the gradient of shift {shift} s is not finite")
    } else {
        format!("shift {shift} s is not finite")
    }
}

/// `e` and its causes as one line, `: `-separated (for an error that holds its cause as
/// text, such as the integrator's).
pub(super) fn with_causes(e: &dyn std::error::Error) -> String {
    let mut s = e.to_string();
    let mut cause = e.source();
    while let Some(c) = cause {
        s.push_str(": ");
        s.push_str(&c.to_string());
        cause = c.source();
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The texts users read: the model's own error as it is, a shift or its gradient, a
    /// missing Hessian, an external error with its causes.
    #[test]
    fn term_errors_read_as_their_causes() {
        let e = TermError::from(DynamicsError::MassMatrix { pivot: 3 });
        assert_eq!(e.to_string(), "mass matrix not positive definite at pivot 3");
        let e = TermError::NonFiniteShift { shift: f64::NAN };
        assert_eq!(e.to_string(), "shift NaN s is not finite");
        let e = TermError::NonFiniteShift { shift: 0.25 };
        assert_eq!(e.to_string(), "the gradient of shift 0.25 s is not finite");
        assert_eq!(TermError::NoHessian.to_string(), "no Hessian provided");
        let e = TermError::external("outside the table");
        assert_eq!(with_causes(&e), "outside the table");
        assert!(e.is_recoverable());
    }
}
