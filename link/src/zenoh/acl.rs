//! The access control central's router enforces when its policy authenticates zenoh clients
//! (zenoh users, client certificates, or both): each identity's sessions are confined to the
//! keys that carry its name (see [`super::keys`]). Everything not allowed below is denied.
//!
//! For identity `N`, a session whose zenoh user is `N`, or whose TLS certificate's common
//! name is `N`, may:
//!
//! | flow    | message                         | key expression     | what for                      |
//! |---------|---------------------------------|--------------------|-------------------------------|
//! | ingress | `put`                           | `tca/up/N/*`       | its frames to central         |
//! | ingress | `declare_subscriber`            | `tca/down/N/*`     | subscribing to its frames     |
//! | egress  | `put`                           | `tca/down/N/*`     | receiving them                |
//! | egress  | `declare_subscriber`            | `tca/up/N/*`       | learning that central listens |
//! | ingress | `liveliness_token`              | `tca/alive/N/*`    | saying it is alive            |
//! | ingress | `declare_liveliness_subscriber` | `tca/central`      | watching central              |
//! | egress  | `liveliness_token`              | `tca/central`      | seeing central's token        |
//!
//! So a session cannot publish as another identity, read another identity's frames, see other
//! modules' tokens, declare central's token or another module's, or query anything. Sessions
//! that share an identity share its keys: give each module its own identity to keep modules
//! apart from each other. Central's own session, inside the router, is not subject to it.
//!
//! With both authenticators, a session is a zenoh user and, on a `tls/` (or `quic/`) link, a
//! certificate's common name too. zenoh lets a message through when any subject the session
//! matches allows it, so a session holding one identity's password and another's certificate
//! must not match both identities' subjects: on those links the subject is the user *and* the
//! certificate of one identity together, and a user alone is a subject only on links without
//! certificates. A session whose user and certificate name different identities matches no
//! subject and is denied everything.

use serde_json::{Value, json};

use super::keys::{
    CENTRAL_ALIVE_KEY, alive_key_pattern, check_identity_name, down_key_pattern, up_key_pattern,
};
use crate::{LinkError, Result};

/// How the router knows who a session is.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Authenticators {
    /// By its zenoh user (`transport/auth/usrpwd`).
    pub users: bool,
    /// By the common name of its TLS client certificate (mutual TLS).
    pub certificates: bool,
}

impl Authenticators {
    /// Whether the router can tell anyone apart.
    pub fn any(self) -> bool {
        self.users || self.certificates
    }
}

/// zenoh's link protocols that carry no client certificate: with both authenticators, a
/// zenoh user alone is an identity only on these.
const LINKS_WITHOUT_CERTIFICATES: &[&str] = &[
    "tcp",
    "udp",
    "serial",
    "unixpipe",
    "unixsock-stream",
    "vsock",
    "ws",
];

fn rule(id: String, flow: &str, message: &str, key: String) -> Value {
    json!({
        "id": id,
        "flows": [flow],
        "messages": [message],
        "key_exprs": [key],
        "permission": "allow",
    })
}

/// zenoh's `access_control` configuration confining each of `identities` to its own keys
/// (see the module documentation), with subjects by zenoh user and/or certificate common name
/// as `by` says. Everything else is denied, also to sessions that match no subject.
pub fn access_control(identities: &[String], by: Authenticators) -> Result<Value> {
    if !by.any() {
        return Err(LinkError::Config(
            "access control needs an authenticator: a zenoh users file or TLS client \
             certificates"
                .into(),
        ));
    }
    let (mut rules, mut subjects, mut policies) = (Vec::new(), Vec::new(), Vec::new());
    for n in identities {
        check_identity_name(n).map_err(LinkError::Config)?;
        let ids = [
            rule(format!("{n}/up"), "ingress", "put", up_key_pattern(n)),
            rule(
                format!("{n}/down-subscribe"),
                "ingress",
                "declare_subscriber",
                down_key_pattern(n),
            ),
            rule(format!("{n}/down"), "egress", "put", down_key_pattern(n)),
            rule(
                format!("{n}/up-route"),
                "egress",
                "declare_subscriber",
                up_key_pattern(n),
            ),
            rule(
                format!("{n}/alive"),
                "ingress",
                "liveliness_token",
                alive_key_pattern(n),
            ),
            rule(
                format!("{n}/central-watch"),
                "ingress",
                "declare_liveliness_subscriber",
                CENTRAL_ALIVE_KEY.into(),
            ),
            rule(
                format!("{n}/central-token"),
                "egress",
                "liveliness_token",
                CENTRAL_ALIVE_KEY.into(),
            ),
        ];
        let rule_ids: Vec<Value> = ids.iter().map(|r| r["id"].clone()).collect();
        rules.extend(ids);
        let mut subject_ids = Vec::new();
        let mut subject = |suffix: &str, mut value: Value| {
            let id = format!("{n}/{suffix}");
            value["id"] = json!(id);
            subjects.push(value);
            subject_ids.push(id);
        };
        if by.users && by.certificates {
            subject(
                "user",
                json!({ "usernames": [n], "link_protocols": LINKS_WITHOUT_CERTIFICATES }),
            );
            subject(
                "user-and-certificate",
                json!({ "usernames": [n], "cert_common_names": [n] }),
            );
        } else if by.users {
            subject("user", json!({ "usernames": [n] }));
        } else {
            subject("certificate", json!({ "cert_common_names": [n] }));
        }
        policies.push(json!({ "id": n, "rules": rule_ids, "subjects": subject_ids }));
    }
    Ok(json!({
        "enabled": true,
        "default_permission": "deny",
        "rules": rules,
        "subjects": subjects,
        "policies": policies,
    }))
}

/// How many messages from clients `router`'s access control has refused since it started
/// (`router` is the router's own session): frames published on another identity's keys, subscriptions, liveliness tokens and
/// queries outside the session's own keys. zenoh drops them at the router and counts them in
/// its statistics (the `rx` dropped-message histograms labelled `access-control`, summed over
/// every transport, also closed ones), read through the router's admin space (which [`super::router_config_secured`] turns on with
/// access control).
pub async fn refusals(router: &zenoh::Session) -> Result<u64> {
    let selector = format!(
        "@/{}/router/metrics?per_transport=false;per_link=false;per_key=false;\
         disconnected=true;compression=false;descriptors=false",
        router.zid()
    );
    let replies = router
        .get(selector)
        .await
        .map_err(|e| LinkError::Open(format!("cannot read the router's statistics: {e}")))?;
    let mut total = 0;
    while let Ok(reply) = replies.recv_async().await {
        if let Ok(sample) = reply.result() {
            let text = sample.payload().try_to_string().unwrap_or_default();
            total += access_control_drops(&text);
        }
    }
    Ok(total)
}

/// Sums the counts of messages received and dropped by access control in zenoh's metrics
/// text (OpenMetrics).
fn access_control_drops(metrics: &str) -> u64 {
    metrics
        .lines()
        .filter_map(|line| {
            let (name, rest) = line.split_once('{')?;
            let (labels, value) = rest.rsplit_once('}')?;
            let wanted = name.contains("rx_network_message_dropped_payload")
                && name.ends_with("_count")
                && labels.contains("reason=\"access-control\"");
            wanted.then(|| value.trim().parse::<f64>().ok())?
        })
        .map(|v| v as u64)
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_identity_gets_its_own_keys_and_subjects() {
        let by = Authenticators {
            users: true,
            certificates: true,
        };
        let acl = access_control(&["gait".into(), "ltm".into()], by).unwrap();
        assert_eq!(acl["default_permission"], "deny");
        assert_eq!(acl["rules"].as_array().unwrap().len(), 14);
        assert_eq!(acl["subjects"].as_array().unwrap().len(), 4);
        let gait = &acl["policies"][0];
        assert_eq!(
            gait["subjects"],
            json!(["gait/user", "gait/user-and-certificate"])
        );
        // A login alone counts only where there is no certificate; with one, the login and
        // the certificate must name the same identity.
        let user = &acl["subjects"][0];
        assert!(
            !user["link_protocols"]
                .as_array()
                .unwrap()
                .iter()
                .any(|p| p == "tls" || p == "quic"),
            "{user}"
        );
        let both = &acl["subjects"][1];
        assert_eq!(both["usernames"], json!(["gait"]));
        assert_eq!(both["cert_common_names"], json!(["gait"]));
        let text = acl.to_string();
        assert!(text.contains("\"tca/up/gait/*\""), "{text}");
        assert!(!text.contains("tca/up/*"), "{text}");
        // It is a configuration zenoh takes.
        let mut config = zenoh::Config::default();
        config.insert_json5("access_control", &text).unwrap();
    }

    #[test]
    fn one_authenticator_makes_one_subject_per_identity() {
        for (by, key) in [
            (
                Authenticators {
                    users: true,
                    certificates: false,
                },
                "usernames",
            ),
            (
                Authenticators {
                    users: false,
                    certificates: true,
                },
                "cert_common_names",
            ),
        ] {
            let acl = access_control(&["gait".into(), "ltm".into()], by).unwrap();
            let subjects = acl["subjects"].as_array().unwrap();
            assert_eq!(subjects.len(), 2);
            assert_eq!(subjects[1][key], json!(["ltm"]));
            assert!(subjects[1].get("link_protocols").is_none(), "{acl}");
        }
    }

    #[test]
    fn no_authenticator_or_a_bad_name_is_refused() {
        assert!(access_control(&["gait".into()], Authenticators::default()).is_err());
        let by = Authenticators {
            users: true,
            certificates: false,
        };
        let err = access_control(&["a/b".into()], by).unwrap_err();
        assert!(err.to_string().contains("\"a/b\""), "{err}");
    }

    #[test]
    fn access_control_drops_are_summed_from_the_metrics() {
        let text = "# TYPE x histogram\n\
            zenoh_rx_network_message_dropped_payload_bytes_count{message=\"put\",reason=\"access-control\"} 3\n\
            zenoh_rx_network_message_dropped_payload_bytes_sum{message=\"put\",reason=\"access-control\"} 300\n\
            zenoh_rx_network_message_dropped_payload_bytes_count{message=\"declare\",reason=\"access-control\"} 2\n\
            zenoh_tx_network_message_dropped_payload_bytes_count{message=\"put\",reason=\"access-control\"} 7\n\
            zenoh_rx_network_message_dropped_payload_bytes_count{message=\"put\",reason=\"congestion\"} 5\n\
            # EOF\n";
        assert_eq!(access_control_drops(text), 5);
    }
}
