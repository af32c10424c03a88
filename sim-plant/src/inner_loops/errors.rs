//! Errors of the inner loops: bad parameters at construction, bad inputs per step.

/// A parameter value a controller cannot work with (rejected at construction).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("inner-loop parameter `{key}`: {msg}")]
pub struct ParamsError {
    /// Field name, prefixed by the component (`rate.p`, `position.xy_p`, ...).
    pub key: &'static str,
    /// What is wrong, with the value.
    pub msg: String,
}

/// Why one controller step was rejected. The controller's state is left untouched; the
/// chain ([`super::MultirotorInnerLoops`]) then holds its previous output and counts the step.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum StepError {
    /// The time step is NaN, infinite, zero or negative.
    #[error("time step dt = {dt} s must be finite and > 0")]
    InvalidDt { dt: f64 },
    /// A state or setpoint input contains NaN or infinity where a number is required.
    #[error("input `{name}` is not finite")]
    NonFinite { name: &'static str },
    /// A trajectory setpoint PX4 would reject (an axis without any setpoint, x/y not in
    /// pairs, or a controlled axis without a valid state estimate).
    #[error("trajectory setpoint rejected: {reason}")]
    InvalidSetpoint { reason: &'static str },
}

pub(crate) fn check_positive(key: &'static str, v: f64) -> Result<(), ParamsError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(ParamsError {
            key,
            msg: format!("{v} must be finite and > 0"),
        })
    }
}

pub(crate) fn check_non_negative(key: &'static str, v: f64) -> Result<(), ParamsError> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(ParamsError {
            key,
            msg: format!("{v} must be finite and >= 0"),
        })
    }
}

pub(crate) fn check_range(key: &'static str, v: f64, lo: f64, hi: f64) -> Result<(), ParamsError> {
    if v.is_finite() && (lo..=hi).contains(&v) {
        Ok(())
    } else {
        Err(ParamsError {
            key,
            msg: format!("{v} must be in [{lo}, {hi}]"),
        })
    }
}

pub(crate) fn check_dt(dt: f64) -> Result<(), StepError> {
    if dt.is_finite() && dt > 0.0 {
        Ok(())
    } else {
        Err(StepError::InvalidDt { dt })
    }
}

pub(crate) fn check_finite3(
    name: &'static str,
    v: &nalgebra::Vector3<f64>,
) -> Result<(), StepError> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(StepError::NonFinite { name })
    }
}

pub(crate) fn check_finite_quat(
    name: &'static str,
    q: &nalgebra::UnitQuaternion<f64>,
) -> Result<(), StepError> {
    if q.coords.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(StepError::NonFinite { name })
    }
}
