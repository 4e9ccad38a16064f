//! Why an NLP evaluation failed, and whether the solver may step around it.

/// A boxed cause, kept as the error's source.
pub type Cause = Box<dyn std::error::Error + Send + Sync + 'static>;

/// Failure of an [`Nlp`](super::Nlp) evaluation.
///
/// The line search treats the two kinds differently: at a trial point a
/// [`Recoverable`](EvalError::Recoverable) failure (an integrator that cannot take a step,
/// a model outside its domain) means "too far", and the step is shortened; a
/// [`Fatal`](EvalError::Fatal) one (a malformed problem, invalid integrator settings)
/// fails at every point, so the solve stops at once and names its cause.
#[derive(Debug, thiserror::Error)]
pub enum EvalError {
    /// The point cannot be evaluated, but a nearby one may be.
    #[error("the evaluation failed at this point")]
    Recoverable(#[source] Cause),
    /// The problem cannot be evaluated at any point.
    #[error("the problem cannot be evaluated")]
    Fatal(#[source] Cause),
}

impl EvalError {
    /// A recoverable failure with a plain message as its cause.
    pub fn recoverable(message: impl Into<String>) -> Self {
        EvalError::Recoverable(message.into().into())
    }

    /// A fatal failure with a plain message as its cause.
    pub fn fatal(message: impl Into<String>) -> Self {
        EvalError::Fatal(message.into().into())
    }

    /// Whether the line search may backtrack from it.
    pub fn is_recoverable(&self) -> bool {
        matches!(self, EvalError::Recoverable(_))
    }

    /// The failure and its causes as one line (for a status or a log).
    pub fn chain(&self) -> String {
        let mut s = self.to_string();
        let mut src = std::error::Error::source(self);
        while let Some(c) = src {
            s.push_str(": ");
            s.push_str(&c.to_string());
            src = c.source();
        }
        s
    }
}
