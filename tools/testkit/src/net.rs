//! Free loopback ports and endpoints, for centrals that listen over zenoh in a test.

/// A TCP port on loopback that is free now.
pub fn free_port() -> u16 {
    tca_link::net::free_loopback_port().expect("a free loopback port")
}

/// A zenoh endpoint on a free loopback port, e.g. `tcp/127.0.0.1:40711`.
pub fn free_endpoint() -> String {
    tca_link::net::free_loopback_endpoint().expect("a free loopback port")
}
