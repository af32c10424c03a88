//! Commander parameters: PX4 v1.16 defaults, each named after its PX4 parameter.

use serde::Deserialize;

use super::land_detector::LandDetectorParams;
use super::stream::OffboardAvailability;

/// Where the vehicle goes when the offboard stream is lost while armed in offboard.
///
/// PX4 v1.16: the offboard-loss mode fallback uses COM_OBL_RC_ACT (default 0, Position). With
/// no RC, the backport of PX4 PR #26289 (#26391, "Prevent Offboard to Position without RC")
/// replaces that manual-mode fallback by the RC-loss action NAV_RCL_ACT (default Return), and
/// Return cannot run indoors without a global position and falls through to Land
/// (FailsafeBase::getSelectedAction). Hence `Land` by default for our motion-capture arena
/// without RC. `Position` reproduces v1.16.0 before that fix (or a setup with RC).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OffboardLossAction {
    /// AUTO.LAND: descend at MPC_LAND_SPEED holding x/y, then auto-disarm.
    Land,
    /// AUTO.LOITER: hold the position where the loss happened.
    Hold,
    /// POSCTL: hold the position where the loss happened (sticks centred).
    Position,
}

/// Commander configuration.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CommanderParams {
    /// COM_OF_LOSS_T, s: the stream counts as lost this long after the last message. Default 1.0.
    pub offboard_loss_timeout_s: f64,
    /// When offboard counts as available. Default: the documented 2 Hz / 1 s rule.
    pub offboard_availability: OffboardAvailability,
    /// Failsafe mode on offboard loss. Default Land (see [`OffboardLossAction`]).
    pub offboard_loss_action: OffboardLossAction,
    /// An RC transmitter is connected (manual-control modes can run). Default false.
    pub rc_present: bool,
    /// MPC_LAND_SPEED, m/s, descent speed in Land (no distance sensor, so no crawl). Default 0.7.
    pub land_speed_mps: f64,
    /// COM_DISARM_LAND, s: auto-disarm after this long landed (<= 0 disables). Default 2.0.
    pub disarm_land_s: f64,
    /// COM_DISARM_PRFLT, s: auto-disarm if armed this long (+ spool-up) without taking off
    /// (<= 0 disables). Default 10.0.
    pub disarm_preflight_s: f64,
    /// COM_SPOOLUP_TIME, s. Default 1.0.
    pub spoolup_time_s: f64,
    /// The land detector's parameters.
    pub land_detector: LandDetectorParams,
}

impl Default for CommanderParams {
    fn default() -> Self {
        CommanderParams {
            offboard_loss_timeout_s: 1.0,
            offboard_availability: OffboardAvailability::default(),
            offboard_loss_action: OffboardLossAction::Land,
            rc_present: false,
            land_speed_mps: 0.7,
            disarm_land_s: 2.0,
            disarm_preflight_s: 10.0,
            spoolup_time_s: 1.0,
            land_detector: LandDetectorParams::default(),
        }
    }
}

/// A commander parameter the emulation cannot use.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("commander parameter `{key}` = {value}: {msg}")]
pub struct CommanderParamsError {
    pub key: &'static str,
    pub value: f64,
    pub msg: &'static str,
}

impl CommanderParams {
    /// Checks that every value is finite, that times, speeds and thresholds that must be
    /// positive are, and that the throttle levels are ordered within 0..1.
    pub fn validate(&self) -> Result<(), CommanderParamsError> {
        let err = |key, value, msg| Err(CommanderParamsError { key, value, msg });
        let mut positive = vec![
            ("offboard_loss_timeout_s", self.offboard_loss_timeout_s),
            ("land_speed_mps", self.land_speed_mps),
        ];
        if let OffboardAvailability::Documented {
            min_rate_hz,
            min_duration_s,
        } = self.offboard_availability
        {
            positive.push(("offboard_availability.min_rate_hz", min_rate_hz));
            positive.push(("offboard_availability.min_duration_s", min_duration_s));
        }
        positive.extend(self.land_detector.entries());
        for (key, value) in positive {
            if !(value.is_finite() && value > 0.0) {
                return err(key, value, "must be finite and > 0");
            }
        }
        for (key, value) in [
            ("disarm_land_s", self.disarm_land_s),
            ("disarm_preflight_s", self.disarm_preflight_s),
            ("spoolup_time_s", self.spoolup_time_s),
        ] {
            if !value.is_finite() {
                return err(key, value, "must be finite");
            }
        }
        let ld = &self.land_detector;
        if !(ld.thr_min < ld.thr_hover && ld.thr_hover <= 1.0) {
            let msg = "need thr_min < thr_hover <= 1";
            return err("land_detector.thr_hover", ld.thr_hover, msg);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_validate_and_parse_partially() {
        CommanderParams::default().validate().unwrap();
        let p: CommanderParams = toml::from_str(
            "offboard_loss_action = \"hold\"\n\
             offboard_availability = { rule = \"last_message_age\" }\n\
             [land_detector]\ntrigger_time_s = 0.5\n",
        )
        .unwrap();
        assert_eq!(p.offboard_loss_action, OffboardLossAction::Hold);
        assert_eq!(
            p.offboard_availability,
            OffboardAvailability::LastMessageAge
        );
        assert_eq!(p.land_detector.trigger_time_s, 0.5);
        assert_eq!(p.land_detector.z_vel_max_mps, 0.25);
        p.validate().unwrap();
        assert!(toml::from_str::<CommanderParams>("com_of_loss_t = 1.0\n").is_err());
    }

    #[test]
    fn validate_names_the_key() {
        let p = CommanderParams {
            offboard_loss_timeout_s: 0.0,
            ..CommanderParams::default()
        };
        assert_eq!(p.validate().unwrap_err().key, "offboard_loss_timeout_s");
        let p = CommanderParams {
            offboard_availability: OffboardAvailability::Documented {
                min_rate_hz: f64::NAN,
                min_duration_s: 1.0,
            },
            ..CommanderParams::default()
        };
        assert_eq!(
            p.validate().unwrap_err().key,
            "offboard_availability.min_rate_hz"
        );
        let mut p = CommanderParams::default();
        p.land_detector.thr_hover = 0.1;
        let e = p.validate().unwrap_err();
        assert_eq!(e.key, "land_detector.thr_hover");
        assert!(e.to_string().contains("thr_hover"));
    }
}
