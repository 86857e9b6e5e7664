//! The registration policy applied to what a module sends (registrations are checked in
//! `registry`). Refused sends are logged as problems and answered with
//! [`RouteError::NotPermitted`]; nothing of them is routed.

use tca_messages::control::{AuthHello, ControlRequest, MonitorAction};
use tca_messages::{Class, Envelope, ModuleName, RouteError, decode_data, encode, encode_data};

use super::{Action, Central, LinkId};

impl Central {
    /// Checks `envelope` from `module` against its grant.
    pub(super) fn permit(
        &mut self,
        link: LinkId,
        module: &ModuleName,
        envelope: &Envelope,
        out: &mut Vec<Action>,
    ) -> Result<(), RouteError> {
        let Some(grant) = self.modules.get(module).and_then(|m| m.grant.as_ref()) else {
            return Ok(());
        };
        let names_sent: Vec<String> = match envelope.class {
            Class::Query | Class::Inform | Class::Exception | Class::Goal | Class::Command => {
                vec![envelope.name.to_string()]
            }
            Class::Control => {
                let mut v = vec![envelope.name.to_string()];
                if let Ok(ControlRequest::Monitor(m)) =
                    ControlRequest::decode(envelope.name.as_str(), &envelope.data)
                {
                    v.push(m.query.to_string());
                    match m.action {
                        MonitorAction::Raise { name, .. } | MonitorAction::Send { name, .. } => {
                            v.push(name.to_string())
                        }
                    }
                }
                v
            }
            // Answers to what central delivered, checked by the routing itself.
            _ => return Ok(()),
        };
        for name in names_sent {
            if let Err(rule) = grant.may_send(&name) {
                let error = RouteError::NotPermitted {
                    module: module.to_string(),
                    identity: grant.identity.clone(),
                    action: "send".into(),
                    name,
                    rule,
                };
                self.problem(
                    Some(link),
                    Some(module.clone()),
                    error.to_string(),
                    &[],
                    out,
                );
                return Err(error);
            }
        }
        Ok(())
    }

    /// Checks that `module` may register `name`; the error names the rule.
    pub(super) fn permit_registration(
        &self,
        module: &ModuleName,
        name: &str,
    ) -> Result<(), String> {
        let Some(grant) = self.modules.get(module).and_then(|m| m.grant.as_ref()) else {
            return Ok(());
        };
        grant.may_register(name).map_err(|rule| {
            RouteError::NotPermitted {
                module: module.to_string(),
                identity: grant.identity.clone(),
                action: "register".into(),
                name: name.to_owned(),
                rule,
            }
            .to_string()
        })
    }
}

/// A `tca.helloAuth` frame with its secret blanked, for the log.
pub(super) fn redacted_hello(envelope: &Envelope) -> Option<bytes::Bytes> {
    let mut copy = envelope.clone();
    match decode_data::<AuthHello>(&envelope.data) {
        Ok(mut hello) => {
            hello.credentials.secret = "***".into();
            copy.data = encode_data(&hello).ok()?;
        }
        Err(_) => copy.data.clear(),
    }
    encode(&copy).ok().map(bytes::Bytes::from)
}
