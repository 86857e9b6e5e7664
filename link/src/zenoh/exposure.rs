//! Whether a zenoh endpoint can be reached from other machines.
//!
//! Central refuses to listen on such an endpoint without a policy (unless told it is
//! insecure on purpose): an open router on a network admits every client that finds it.

use std::net::IpAddr;

/// Who can reach an endpoint central listens on.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Exposure {
    /// Only this machine: a loopback address, `localhost` or a Unix socket.
    ThisMachine,
    /// Other machines too; the string says why (the address as written).
    Network(String),
}

/// Classifies a zenoh endpoint such as `tcp/127.0.0.1:7447`, `tcp/0.0.0.0:7447`,
/// `udp/[::1]:7447` or `unixsock-stream//tmp/tca.sock`. A host name other than `localhost`
/// counts as reachable from the network (it may resolve to any interface).
pub fn exposure(endpoint: &str) -> Exposure {
    let without_config = endpoint.split(['?', '#']).next().unwrap_or(endpoint).trim();
    let Some((protocol, address)) = without_config.split_once('/') else {
        return Exposure::Network(endpoint.to_owned());
    };
    if protocol.starts_with("unixsock") {
        return Exposure::ThisMachine;
    }
    let host = match address.rsplit_once(':') {
        Some((host, _port)) => host,
        None => address,
    };
    let host = host.trim_start_matches('[').trim_end_matches(']');
    let host = host.split('%').next().unwrap_or(host);
    let loopback = if host.eq_ignore_ascii_case("localhost") {
        true
    } else {
        host.parse::<IpAddr>().is_ok_and(|ip| ip.is_loopback())
    };
    if loopback {
        Exposure::ThisMachine
    } else {
        Exposure::Network(format!("{host} in {endpoint}"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn loopback_and_unix_sockets_stay_on_this_machine() {
        for e in [
            "tcp/127.0.0.1:7447",
            "tcp/127.3.4.5:1",
            "udp/[::1]:7447",
            "tcp/localhost:7447",
            "tcp/LOCALHOST:7447",
            "quic/127.0.0.1:7447?iface=lo",
            "unixsock-stream//tmp/tca.sock",
        ] {
            assert_eq!(exposure(e), Exposure::ThisMachine, "{e}");
        }
    }

    #[test]
    fn every_interface_addresses_and_host_names_reach_the_network() {
        for e in [
            "tcp/0.0.0.0:7447",
            "tcp/[::]:7447",
            "tcp/192.168.1.20:7447",
            "udp/10.0.0.1:7447",
            "tcp/robot.example.org:7447",
            "tcp/127.0.0.1.example.org:7447",
            "no-protocol",
        ] {
            assert!(matches!(exposure(e), Exposure::Network(_)), "{e}");
        }
    }
}
