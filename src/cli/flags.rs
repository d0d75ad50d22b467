//! The command line's names for the parameters that library errors name: the runtime returns
//! [`RuntimeError::InvalidParam`] naming a [`Param`], the measurement crate
//! [`MeasureError::InvalidParam`] naming a [`ReplayParam`]; the message the user sees names
//! the flag.

use oslf_measure::replay::ReplayParam;
use oslf_measure::MeasureError;
use oslf_runtime::{Param, RuntimeError};

/// The flag that sets `param`.
pub fn flag(param: Param) -> &'static str {
    match param {
        Param::CacheMegabytes => "--cache-mb",
        Param::RamMegabytes => "--ram-mb",
        Param::ProxyBox => "--proxy-box",
    }
}

/// The flag that sets the replay parameter `param`.
pub fn replay_flag(param: ReplayParam) -> &'static str {
    match param {
        ReplayParam::StillFrames => "--still-frames",
        ReplayParam::OrbitFrames => "--frames",
        ReplayParam::OrbitDegrees => "--orbit-degrees",
    }
}

/// `e` with the parameter that a [`RuntimeError::InvalidParam`] or
/// [`MeasureError::InvalidParam`] anywhere in its chain names called by its flag (the rest of
/// the message, context included, unchanged); other errors as they are.
pub fn name_flags(e: anyhow::Error) -> anyhow::Error {
    let names = e.chain().find_map(|cause| {
        match cause.downcast_ref::<RuntimeError>() {
            Some(RuntimeError::InvalidParam { param, .. }) => {
                return Some((param.name(), flag(*param)))
            }
            Some(_) => return None,
            None => {}
        }
        match cause.downcast_ref::<MeasureError>() {
            Some(MeasureError::InvalidParam { param, .. }) => {
                Some((param.name(), replay_flag(*param)))
            }
            _ => None,
        }
    });
    match names {
        Some((library, cli)) => {
            let library = format!("invalid parameter: {library}");
            let cli = format!("invalid parameter: {cli}");
            anyhow::anyhow!("{}", format!("{e:#}").replacen(&library, &cli, 1))
        }
        None => e,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parameter_errors_name_the_flag_and_keep_their_context() {
        let e = anyhow::Error::from(RuntimeError::InvalidParam {
            param: Param::CacheMegabytes,
            problem: "0.000001 holds no cube map (0.010 MB each)".into(),
        })
        .context("rendering");
        assert_eq!(
            name_flags(e).to_string(),
            "rendering: invalid parameter: --cache-mb 0.000001 holds no cube map (0.010 MB each)"
        );
        let e = anyhow::Error::from(MeasureError::InvalidParam {
            param: ReplayParam::OrbitDegrees,
            problem: "NaN must be a finite number".into(),
        });
        assert_eq!(
            name_flags(e).to_string(),
            "invalid parameter: --orbit-degrees NaN must be a finite number"
        );
        let other = anyhow::anyhow!("something else");
        assert_eq!(name_flags(other).to_string(), "something else");
    }
}
