//! The live view's WebSocket server speaks the Foxglove protocol: a client that connects
//! with the `foxglove.sdk.v1` subprotocol (the Foxglove WebSocket protocol as the SDK serves it) sees the channels advertised with their
//! schemas, subscribes to one and receives its messages.

use futures::{SinkExt, StreamExt};
use tca_messages::*;
use tca_single_leg_messages as leg;
use tokio_tungstenite::tungstenite::Message as Ws;
use tokio_tungstenite::tungstenite::client::IntoClientRequest;

fn reply(map: &leg::MapGrid) -> Envelope {
    Envelope {
        id: MessageId::new(3, 2),
        class: Class::Reply,
        name: MessageName::new("mapRegion").unwrap(),
        sender: ModuleName::new("ltm").unwrap(),
        context: None,
        node: None,
        correlation: Some(MessageId::new(4, 1)),
        cause: None,
        timestamp_ns: 5,
        options: SendOptions::default(),
        redelivery: 0,
        data: encode_data(map).unwrap(),
    }
}

type Client =
    tokio_tungstenite::WebSocketStream<tokio_tungstenite::MaybeTlsStream<tokio::net::TcpStream>>;

async fn next(ws: &mut Client, deadline: tokio::time::Instant) -> Ws {
    tokio::time::timeout_at(deadline, ws.next())
        .await
        .expect("the server said nothing in time")
        .expect("the server closed the connection")
        .expect("a WebSocket error")
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_client_subscribes_to_a_map_and_receives_it() {
    let mut view = tca_foxglove::LiveView::start("127.0.0.1", 0).await.unwrap();
    let mut formats = tca_foxglove::traffic::FormatTable::new();
    formats.insert(
        MessageName::new("mapRegion").unwrap(),
        tca_foxglove::traffic::Formats {
            format: <leg::MapRegion as Message>::format().unwrap(),
            reply: <leg::MapRegion as Message>::reply_format().unwrap(),
        },
    );
    view.set_formats(formats);
    let map = leg::MapGrid {
        kind: leg::MapKind::Elevation,
        origin_x_m: 0.0,
        origin_y_m: 0.0,
        resolution_m: 0.25,
        nx: 2,
        ny: 1,
        cells: vec![
            leg::MapCell::Unknown,
            leg::MapCell::Known {
                value: 1.5,
                sigma_m: 0.1,
            },
        ],
    };
    // The first message makes the channels.
    view.publish(&reply(&map), 1).unwrap();

    let mut request = format!("ws://127.0.0.1:{}", view.port())
        .into_client_request()
        .unwrap();
    request
        .headers_mut()
        .insert("sec-websocket-protocol", "foxglove.sdk.v1".parse().unwrap());
    let (mut ws, _) = tokio_tungstenite::connect_async(request).await.unwrap();
    let deadline = tokio::time::Instant::now() + std::time::Duration::from_secs(10);
    // serverInfo, then the advertisement of both channels.
    let mut grid_channel = None;
    let mut traffic_schema = None;
    while grid_channel.is_none() || traffic_schema.is_none() {
        if let Ws::Text(t) = next(&mut ws, deadline).await {
            let v: serde_json::Value = serde_json::from_str(&t).unwrap();
            if v["op"] == "advertise" {
                for c in v["channels"].as_array().unwrap() {
                    if c["topic"] == "/map/elevation" {
                        assert_eq!(c["schemaName"], "foxglove.Grid");
                        assert_eq!(c["encoding"], "protobuf");
                        grid_channel = c["id"].as_u64();
                    }
                    if c["topic"] == "mapRegion/reply" {
                        assert_eq!(c["schemaEncoding"], "jsonschema");
                        traffic_schema = Some(c["schema"].as_str().unwrap().to_owned());
                    }
                }
            }
        }
    }
    let schema: serde_json::Value = serde_json::from_str(&traffic_schema.unwrap()).unwrap();
    assert_eq!(schema["properties"]["data"]["title"], "MapGrid");
    let sub = serde_json::json!({
        "op": "subscribe",
        "subscriptions": [{"id": 7, "channelId": grid_channel.unwrap()}],
    });
    ws.send(Ws::Text(sub.to_string().into())).await.unwrap();
    // Publish until the subscription takes effect and a message arrives.
    let grid = loop {
        view.publish(&reply(&map), 2).unwrap();
        match tokio::time::timeout(
            std::time::Duration::from_millis(200),
            next(&mut ws, deadline),
        )
        .await
        {
            Ok(Ws::Binary(b)) => break b,
            _ => continue,
        }
    };
    // Message data: opcode 1, subscription id, timestamp, payload.
    assert_eq!(grid[0], 1);
    assert_eq!(u32::from_le_bytes(grid[1..5].try_into().unwrap()), 7);
    use foxglove::Decode;
    let g = foxglove::messages::Grid::decode(&grid[13..]).unwrap();
    assert_eq!(g.column_count, 2);
    let value = f32::from_le_bytes(g.data[12..16].try_into().unwrap());
    assert_eq!(value, 1.5);
    drop(ws);
    view.stop().await;
}
