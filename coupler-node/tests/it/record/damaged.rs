//! MCAP record, damaged files: any flipped byte is read or refused clearly, damage to the
//! summary loses no data, a damaged file is not taken for a killed run, and a record of the old
//! layout is refused with its versions.

use super::*;

/// Byte ranges of the chunks of a file, in order: (offset, length of the whole record).
fn chunks(bytes: &[u8]) -> Vec<(usize, usize)> {
    let summary = mcap::Summary::read(bytes).unwrap().expect("summary");
    let mut out: Vec<_> = summary
        .chunk_indexes
        .iter()
        .map(|c| (c.chunk_start_offset as usize, c.chunk_length as usize))
        .collect();
    out.sort_unstable();
    out
}

/// Issue 11, items 2 and 3: flipping any one byte of a small record (every byte, each flipped
/// by two masks) never panics or aborts a reader; each read is Ok or a clear error; a flip in a
/// chunk's compressed data is always refused with that chunk's index and offset, and recovery
/// then keeps every other chunk.
#[test]
fn issue_11_every_flipped_byte_is_read_or_refused_clearly() {
    let (bytes, _, _) = record_run(3, RecordLevel::Exchange);
    let complete = read_recording(&bytes).unwrap();
    let chunk_ranges = chunks(&bytes);
    let (mut n_ok, mut n_err, mut n_chunk, mut n_neutral) = (0, 0, 0, 0);
    for at in 0..bytes.len() {
        for mask in [0x01u8, 0xFF] {
            let mut bad = bytes.clone();
            bad[at] ^= mask;
            let strict = read_recording(&bad);
            let script = protocol::replay::Script::from_mcap(&bad, NodeKind::Fluid);
            let recovered = recover(&bad);
            // The streamed export reads what the strict reader reads (it checks less: not the
            // summary), and refuses damage naming where it is.
            let streamed = stream_table(&bad[..], &TableFilter::default(), &mut std::io::sink());
            if strict.is_ok() {
                assert!(streamed.is_ok(), "flip at {at}: {:?}", streamed.err());
            }
            if let Err(e) = &streamed {
                let text = e.to_string();
                assert!(
                    text.contains("byte") || text.contains("CRC") || text.contains("decode"),
                    "flip at {at}: streamed: {text}"
                );
            }
            match &strict {
                Ok(rec) => {
                    n_ok += 1;
                    let _ = list_steps(rec);
                    // Read without complaint, so it is not reported as a killed run unless it is one.
                    assert!(
                        !matches!(rec.end, End::CutShort { .. }),
                        "flip at {at} read as cut short"
                    );
                }
                Err(e) => {
                    n_err += 1;
                    let text = e.to_string();
                    assert!(
                        text.contains("byte") || text.contains("CRC"),
                        "flip at {at}: {text}"
                    );
                }
            }
            assert_eq!(
                script.is_ok(),
                strict.is_ok(),
                "flip at {at}: {:?}",
                script.err()
            );
            let recovered = match recovered {
                Ok(recovered) => recovered,
                Err(e) => {
                    // Only bytes that are not MCAP at all are refused.
                    assert!(at < 8, "flip at {at}: recover: {e}");
                    continue;
                }
            };
            // Whatever was dropped is said; whatever was kept reads back.
            let again = read_recording(&recovered.bytes).unwrap();
            assert_eq!(again.messages, recovered.recording.messages);
            if let Some(index) = chunk_ranges
                .iter()
                .position(|&(o, len)| at >= o + 9 + 40 && at < o + len)
            {
                // Inside a chunk's compressed records (past its header).
                let (offset, _) = chunk_ranges[index];
                let err = strict
                    .as_ref()
                    .expect_err("a flipped chunk byte is refused");
                if let RecordError::Read(ScanError::DataCrc { .. }) = err {
                    // The chunk still decompresses to the bytes its CRC covers (an lz4 match
                    // offset pointing at an identical earlier run): nothing is lost, the file
                    // is still refused for its changed byte, and recovery keeps everything.
                    n_neutral += 1;
                    assert_eq!(
                        recovered.recording.messages, complete.messages,
                        "flip at {at}"
                    );
                    assert_eq!(recovered.dropped.len(), 1, "flip at {at}");
                    assert_eq!(recovered.dropped[0].what, "nothing");
                    continue;
                }
                assert!(
                    matches!(
                        err,
                        RecordError::Read(ScanError::ChunkCrc { index: i, offset: o, .. }
                            | ScanError::Chunk { index: i, offset: o, .. })
                            if *i == index && *o == offset
                    ),
                    "flip at {at} (chunk {index} at {offset}): {err}"
                );
                n_chunk += 1;
                assert_eq!(
                    recovered.dropped.len(),
                    1,
                    "flip at {at}: {:?}",
                    recovered.dropped
                );
                assert!(recovered.dropped[0].what == format!("chunk {index}"));
                // Chunk 0 holds the schemas and channels (found again in the summary); every
                // later chunk holds a step's messages, lost with it.
                if index > 0 {
                    assert!(recovered.recording.messages.len() < complete.messages.len());
                }
                assert!(
                    recovered
                        .recording
                        .messages
                        .iter()
                        .all(|m| complete.messages.contains(m))
                );
            }
        }
    }
    eprintln!(
        "{} bytes flipped twice each: {n_ok} reads Ok, {n_err} refused ({n_chunk} naming the \
         damaged chunk, {n_neutral} chunk flips that change no recorded byte)",
        bytes.len()
    );
    assert!(n_err > 0 && n_ok > 0 && n_chunk > n_neutral);
}

/// Issue 11, item 3: damage confined to the summary section loses nothing: the data section is
/// read in full and the damage is reported.
#[test]
fn issue_11_summary_damage_leaves_the_data_readable() {
    let (bytes, _, _) = record_run(3, RecordLevel::Exchange);
    let complete = read_recording(&bytes).unwrap();
    let summary_start = u64::from_le_bytes(
        bytes[bytes.len() - 8 - 20..bytes.len() - 8 - 12]
            .try_into()
            .unwrap(),
    ) as usize;
    assert!(summary_start > 0);
    for at in (summary_start..bytes.len() - 8 - 29).step_by(7) {
        let mut bad = bytes.clone();
        bad[at] ^= 0x5A;
        let rec = read_recording(&bad).unwrap_or_else(|e| panic!("flip at {at}: {e}"));
        assert_eq!(rec.messages, complete.messages, "flip at {at}");
        assert_eq!(rec.metadata, complete.metadata);
        assert!(
            matches!(&rec.end, End::Finished { summary_damage: Some(d) } if d.contains("CRC")),
            "flip at {at}: {:?}",
            rec.end
        );
        assert!(!rec.truncated());
        let script = protocol::replay::Script::from_mcap(&bad, NodeKind::Fluid).unwrap();
        assert!(!script.truncated);
    }
}

/// Issue 11, item 3: a file that ends with the end magic but holds a record running past the
/// end was damaged, not cut short by a kill: refused, with the offset.
#[test]
fn issue_11_a_damaged_file_is_not_called_a_killed_run() {
    let (bytes, _, _) = record_run(3, RecordLevel::Exchange);
    let (offset, _) = chunks(&bytes)[1];
    let mut bad = bytes.clone();
    // The chunk's record length: now far past the end of the file.
    bad[offset + 8] ^= 0x40;
    let err = read_recording(&bad).unwrap_err().to_string();
    assert!(
        err.contains(&format!("at byte {offset}")) && err.contains("damaged, not cut short"),
        "{err}"
    );
    let fixed = recover(&bad).unwrap();
    assert_eq!(fixed.dropped.len(), 1, "{:?}", fixed.dropped);
    assert_eq!(fixed.dropped[0].offset, offset);
    // Chunks 0 and 2 and later are kept.
    assert!(!fixed.recording.messages.is_empty());
    assert!(
        fixed
            .recording
            .topic(DIAGNOSTICS_TOPIC)
            .any(|m| m.step == 2)
    );
    assert!(
        !fixed
            .recording
            .topic(DIAGNOSTICS_TOPIC)
            .any(|m| m.step == 0)
    );
}

/// Issue 15, item 5: a record of the older layout (topics without '/', log time = step) is
/// refused by every reader with an error naming both layouts and protocol versions.
#[test]
fn a_record_of_the_old_layout_is_refused_with_its_versions() {
    let mut w = mcap::WriteOptions::new()
        .profile("")
        .create(Cursor::new(Vec::new()))
        .unwrap();
    w.write_metadata(&mcap::records::Metadata {
        name: "run".into(),
        metadata: [("protocol_version".to_string(), "2".to_string())].into(),
    })
    .unwrap();
    let schema = w
        .add_schema("protocol::wire::Message", "bincode-serde", b"")
        .unwrap();
    let ch = w
        .add_channel(schema, "fluid-to-coupler", "bincode", &Default::default())
        .unwrap();
    w.write_to_known_channel(
        &mcap::records::MessageHeader {
            channel_id: ch,
            sequence: 0,
            log_time: 0,
            publish_time: 0,
        },
        &codec::encode(NodeKind::Fluid, &loads(0, 0, 1)),
    )
    .unwrap();
    w.finish().unwrap();
    let old = w.into_inner().into_inner();
    for err in [
        read_recording(&old).unwrap_err().to_string(),
        recover(&old).unwrap_err().to_string(),
        protocol::replay::Script::from_mcap(&old, NodeKind::Fluid)
            .unwrap_err()
            .to_string(),
    ] {
        assert!(
            err.contains("layout 1")
                && err.contains("protocol version 2")
                && err.contains(&format!(
                    "record layout 2 and protocol version {PROTOCOL_VERSION}"
                )),
            "{err}"
        );
    }
}
