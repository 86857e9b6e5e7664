//! Free loopback ports and endpoints, for centrals that listen over zenoh in a test.

/// A TCP port on loopback that is free now.
pub fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .map(|a| a.port())
        .expect("a free loopback port")
}

/// A zenoh endpoint on a free loopback port, e.g. `tcp/127.0.0.1:40711`.
pub fn free_endpoint() -> String {
    tca_link::zenoh::free_loopback_endpoint().expect("a free loopback port")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn endpoints_are_loopback_tcp() {
        assert!(free_endpoint().starts_with("tcp/127.0.0.1:"));
        assert!(free_port() > 0);
    }
}
