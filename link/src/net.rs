//! Free loopback ports, for tests, benchmarks and tools that start a central of their own.

/// A TCP port on loopback that is free now.
pub fn free_loopback_port() -> std::io::Result<u16> {
    Ok(std::net::TcpListener::bind("127.0.0.1:0")?
        .local_addr()?
        .port())
}

/// A zenoh TCP endpoint on a loopback port that is free now, e.g. `tcp/127.0.0.1:40711`.
pub fn free_loopback_endpoint() -> std::io::Result<String> {
    Ok(format!("tcp/127.0.0.1:{}", free_loopback_port()?))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn endpoints_are_loopback_tcp() {
        assert!(
            free_loopback_endpoint()
                .unwrap()
                .starts_with("tcp/127.0.0.1:")
        );
        assert!(free_loopback_port().unwrap() > 0);
    }
}
