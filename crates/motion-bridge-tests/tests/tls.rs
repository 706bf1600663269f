//! The bridge behind TLS (feature `tls`): the README's certificate set-up, made here with
//! the `openssl` command, a bridge listening on `tls/…` and a remote client that trusts the
//! test's CA — and one that does not, which gets no session.
#![cfg(feature = "tls")]

use core::time::Duration;
use std::path::Path;
use std::process::Command;

use iceoryx2::prelude::ipc;
use motion_bridge_tests::{BridgeThread, DEADLINE, Result, fake, free_port, scratch};
use motion_client::{ClientBuilder, ConnectError};

fn openssl(dir: &Path, args: &[&str]) -> Result {
    let output = Command::new("openssl")
        .current_dir(dir)
        .args(args)
        .output()?;
    if output.status.success() {
        Ok(())
    } else {
        Err(format!(
            "openssl {}: {}",
            args.join(" "),
            String::from_utf8_lossy(&output.stderr)
        )
        .into())
    }
}

/// A CA and a certificate for `localhost` signed by it.
fn certificates(dir: &Path) -> Result {
    openssl(
        dir,
        &[
            "req",
            "-x509",
            "-newkey",
            "rsa:2048",
            "-nodes",
            "-keyout",
            "ca.key",
            "-out",
            "ca.pem",
            "-days",
            "2",
            "-subj",
            "/CN=motion-bridge test CA",
        ],
    )?;
    openssl(
        dir,
        &[
            "req",
            "-newkey",
            "rsa:2048",
            "-nodes",
            "-keyout",
            "bridge.key",
            "-out",
            "bridge.csr",
            "-subj",
            "/CN=localhost",
        ],
    )?;
    std::fs::write(dir.join("san.ext"), "subjectAltName=DNS:localhost\n")?;
    openssl(
        dir,
        &[
            "x509",
            "-req",
            "-in",
            "bridge.csr",
            "-CA",
            "ca.pem",
            "-CAkey",
            "ca.key",
            "-CAcreateserial",
            "-out",
            "bridge.pem",
            "-days",
            "2",
            "-extfile",
            "san.ext",
        ],
    )
}

#[test]
fn a_remote_client_that_trusts_the_bridges_ca_connects_over_tls() -> Result {
    if Command::new("openssl").arg("version").output().is_err() {
        eprintln!("SKIPPED: no openssl command to make the test certificates");
        return Ok(());
    }
    let dir = scratch("bridge-tls")?;
    certificates(&dir)?;
    let bridge_config = dir.join("bridge-zenoh.json5");
    std::fs::write(
        &bridge_config,
        format!(
            "{{ transport: {{ link: {{ tls: {{ listen_private_key: \"{0}/bridge.key\", \
             listen_certificate: \"{0}/bridge.pem\" }} }} }} }}",
            dir.display()
        ),
    )?;
    let client_config = dir.join("client-zenoh.json5");
    std::fs::write(
        &client_config,
        format!(
            "{{ transport: {{ link: {{ tls: {{ root_ca_certificate: \"{}/ca.pem\" }} }} }} }}",
            dir.display()
        ),
    )?;
    let server = fake("bridge-tls")?;
    let port = free_port()?;
    let endpoint = format!("tls/localhost:{port}");
    let _bridge = BridgeThread::start_on(
        server.name(),
        "[[remote]]\nidentity = \"panel\"\nallow = [\"all\"]\n",
        Some(bridge_config),
        &endpoint,
    )?;
    let client = ClientBuilder::new(server.name())
        .connect_timeout(Duration::from_secs(10))
        .remote(&endpoint)
        .identity("panel")
        .zenoh_config(&client_config)
        .connect::<ipc::Service>()?;
    client.wait_ready(DEADLINE)?;
    client.axis("x")?.ramp_to(3.0, 0.0, 0.0)?;
    client.axis("x")?.wait_until_arrived(DEADLINE)?;

    // Without the CA the bridge's certificate is not trusted: no session.
    match ClientBuilder::new(server.name())
        .connect_timeout(Duration::from_millis(500))
        .remote(&endpoint)
        .connect::<ipc::Service>()
    {
        Err(ConnectError::NoBridge { .. }) => {}
        Err(other) => return Err(format!("unexpected error: {other}").into()),
        Ok(_) => return Err("connected without trusting the CA".into()),
    }
    let _ = std::fs::remove_dir_all(&dir);
    Ok(())
}
