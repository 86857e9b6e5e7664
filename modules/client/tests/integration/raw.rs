//! Handlers and sends by name and encoded data (for tools that stand in for modules they were
//! not compiled with, like `tca log replay`), through an in-process central.

use tca_testkit::within;

use tca_messages::control::{Registration, TaskOutcome};
use tca_messages::{Class, DataFormat, MessageName, decode_data, encode_data};
use tca_module::{HandlerError, Module, ModuleError};

fn registration(name: &str, class: Class, reply: Option<DataFormat>) -> Registration {
    Registration {
        name: MessageName::new(name).unwrap(),
        class,
        format: DataFormat::of::<u32>().unwrap(),
        reply,
        replace: false,
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn raw_handlers_answer_raw_sends_and_see_who_asked() {
    let (central, connector) = tca_testkit::in_process_central().await;
    let (seen_tx, mut seen_rx) = tokio::sync::mpsc::unbounded_channel();
    let seen = seen_tx.clone();
    let _doubler = within(
        "raw",
        Module::builder("doubler")
            .handle_raw(
                registration(
                    "double",
                    Class::Query,
                    Some(DataFormat::of::<u32>().unwrap()),
                ),
                move |ctx, data| {
                    let _ = seen.send((ctx.sender().to_string(), ctx.class()));
                    async move {
                        let n: u32 = decode_data(&data).map_err(HandlerError::from)?;
                        encode_data(&(2 * n)).map_err(HandlerError::from)
                    }
                },
            )
            .handle_raw(
                registration("refuse", Class::Goal, None),
                move |ctx, _data| {
                    let _ = seen_tx.send((ctx.sender().to_string(), ctx.class()));
                    async move { Err::<Vec<u8>, _>(HandlerError::new("refused on purpose")) }
                },
            )
            .connect(&connector),
    )
    .await
    .unwrap();
    let asker = within("raw", Module::builder("asker").connect(&connector))
        .await
        .unwrap();

    let reply = within(
        "raw",
        asker.query_raw("double", encode_data(&21u32).unwrap(), None),
    )
    .await
    .unwrap();
    assert_eq!(decode_data::<u32>(&reply).unwrap(), 42);
    assert_eq!(
        seen_rx.recv().await.unwrap(),
        ("asker".to_owned(), Class::Query)
    );

    let task = asker
        .send_watched_raw(Class::Goal, "refuse", encode_data(&1u32).unwrap(), [])
        .unwrap();
    match within("raw", task.outcome()).await.unwrap() {
        TaskOutcome::Failed(reason) => assert!(reason.contains("refused on purpose"), "{reason}"),
        other => panic!("expected a failure, got {other:?}"),
    }
    assert_eq!(
        seen_rx.recv().await.unwrap(),
        ("asker".to_owned(), Class::Goal)
    );

    // Queries go through query_raw; options only apply to goals and commands.
    let err = asker
        .send_raw(Class::Query, "double", vec![], [])
        .unwrap_err();
    assert!(matches!(err, ModuleError::Usage(_)), "{err}");
    let err = asker
        .send_watched_raw(Class::Inform, "double", vec![], [])
        .unwrap_err();
    assert!(err.to_string().contains("goals and commands only"), "{err}");
    central.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn raw_registrations_are_checked_before_connecting() {
    let (central, connector) = tca_testkit::in_process_central().await;
    // A query without a reply format.
    let err = within(
        "raw",
        Module::builder("bad")
            .handle_raw(
                registration("ask", Class::Query, None),
                |_ctx, d| async move { Ok(d) },
            )
            .connect(&connector),
    )
    .await
    .unwrap_err();
    assert!(err.to_string().contains("reply format"), "{err}");
    // A class nobody handles.
    let err = within(
        "raw",
        Module::builder("bad2")
            .handle_raw(
                registration("r", Class::Reply, None),
                |_ctx, d| async move { Ok(d) },
            )
            .connect(&connector),
    )
    .await
    .unwrap_err();
    assert!(err.to_string().contains("only queries, goals"), "{err}");
    central.shutdown().await.unwrap();
}
