//! The command line's names for the parameters that library errors name: the runtime returns
//! [`RuntimeError::InvalidParam`] naming a [`Param`]; the message the user sees names the flag.

use oslf_runtime::{Param, RuntimeError};

/// The flag that sets `param`.
pub fn flag(param: Param) -> &'static str {
    match param {
        Param::CacheMegabytes => "--cache-mb",
        Param::RamMegabytes => "--ram-mb",
        Param::StillFrames => "--still-frames",
        Param::OrbitFrames => "--frames",
        Param::OrbitDegrees => "--orbit-degrees",
        Param::ProxyBox => "--proxy-box",
    }
}

/// `e` with the parameter that a [`RuntimeError::InvalidParam`] anywhere in its chain names
/// called by its flag (the rest of the message, context included, unchanged); other errors as
/// they are.
pub fn name_flags(e: anyhow::Error) -> anyhow::Error {
    let param = e
        .chain()
        .find_map(|cause| match cause.downcast_ref::<RuntimeError>() {
            Some(RuntimeError::InvalidParam { param, .. }) => Some(*param),
            _ => None,
        });
    match param {
        Some(param) => {
            let library = format!("invalid parameter: {}", param.name());
            let cli = format!("invalid parameter: {}", flag(param));
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
        let other = anyhow::anyhow!("something else");
        assert_eq!(name_flags(other).to_string(), "something else");
    }
}
