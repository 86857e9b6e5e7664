//! Handlers are called in the order their messages arrive: what a handler does before its
//! future first waits happens in that order, even on a runtime with several threads and with
//! futures that finish in any order.

use std::sync::{Arc, Mutex};
use std::time::Duration;

use serde::{Deserialize, Serialize};
use tca_messages::control::Registration;
use tca_messages::{Class, DataFormat, MessageName, decode_data, encode_data};
use tca_module::Module;
use tca_testkit::within;

/// A numbered sample: an inform.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct Sample(u32);
tca_messages::message!(Sample: inform "sample");

const SAMPLES: u32 = 2_000;

/// A pause that differs from sample to sample, so that futures end out of order.
fn pause(n: u32) -> Duration {
    Duration::from_micros(u64::from((n * 7919) % 13) * 50)
}

/// Panics, saying where, unless `seen` is 0, 1, 2, ... in order.
fn assert_in_order(seen: &[u32]) {
    assert_eq!(seen.len(), SAMPLES as usize, "every sample is handled once");
    if let Some(k) = (0..SAMPLES).position(|n| seen[n as usize] != n) {
        let to = (k + 5).min(seen.len());
        panic!(
            "handler calls out of arrival order from position {k}: {:?}",
            &seen[k..to]
        );
    }
}

/// A module that only sends.
async fn connect_sender(connector: &tca_module::Connector) -> Module {
    within("sender", Module::builder("sender").connect(connector))
        .await
        .unwrap()
}

async fn wait_for(seen: &Mutex<Vec<u32>>, count: usize) {
    within("every sample handled", async {
        while seen.lock().unwrap().len() < count {
            tokio::time::sleep(Duration::from_millis(10)).await;
        }
    })
    .await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 4)]
async fn typed_handlers_are_called_in_arrival_order() {
    let (central, connector) = tca_testkit::in_process_central().await;
    let seen = Arc::new(Mutex::new(Vec::new()));
    let ended = Arc::new(Mutex::new(Vec::new()));
    let (s, e) = (seen.clone(), ended.clone());
    let _monitor = within(
        "monitor",
        Module::builder("monitor")
            .handle(move |_ctx, sample: Sample| {
                s.lock().unwrap().push(sample.0);
                let e = e.clone();
                async move {
                    tokio::time::sleep(pause(sample.0)).await;
                    e.lock().unwrap().push(sample.0);
                    Ok(())
                }
            })
            .connect(&connector),
    )
    .await
    .unwrap();
    let sender = connect_sender(&connector).await;
    for n in 0..SAMPLES {
        sender.inform(&Sample(n)).unwrap();
    }
    wait_for(&ended, SAMPLES as usize).await;
    let seen = seen.lock().unwrap().clone();
    assert_in_order(&seen);
    // The futures did run beside each other: they ended in another order.
    let ended = ended.lock().unwrap().clone();
    assert_ne!(ended, seen, "the handlers' futures ran one after another");
    central.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 4)]
async fn raw_handlers_are_called_in_arrival_order() {
    let (central, connector) = tca_testkit::in_process_central().await;
    let seen = Arc::new(Mutex::new(Vec::new()));
    let s = seen.clone();
    let registration = Registration {
        name: MessageName::new("rawSample").unwrap(),
        class: Class::Inform,
        format: DataFormat::of::<u32>().unwrap(),
        reply: None,
        replace: false,
    };
    let _monitor = within(
        "monitor",
        Module::builder("monitor")
            .handle_raw(registration, move |_ctx, data| {
                let n: u32 = decode_data(&data).unwrap();
                s.lock().unwrap().push(n);
                async move {
                    tokio::time::sleep(pause(n)).await;
                    Ok(Vec::new())
                }
            })
            .connect(&connector),
    )
    .await
    .unwrap();
    let sender = connect_sender(&connector).await;
    for n in 0..SAMPLES {
        sender
            .send_raw(Class::Inform, "rawSample", encode_data(&n).unwrap(), [])
            .unwrap();
    }
    wait_for(&seen, SAMPLES as usize).await;
    assert_in_order(&seen.lock().unwrap());
    central.shutdown().await.unwrap();
}
