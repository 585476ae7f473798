// Reads MCAP files with @mcap/core, an MCAP implementation independent of ours, and prints
// what it found as one JSON object per file (tests/python/record/mcap_js.py compares it).
//   node check_mcap.mjs FILE...
// Every file is read with the stream reader, CRCs checked (a file without footer, as a killed
// recorder leaves it, reads up to its last complete record: "done" is false, "leftover" the
// bytes of an unfinished record); a file with a footer also with the indexed reader (summary,
// chunk and message indexes), whose messages must be the same.  Exit 1 with the error text
// when a reader rejects a file.
import { readFile } from "node:fs/promises";
import { McapIndexedReader, McapStreamReader } from "@mcap/core";
import { loadDecompressHandlers } from "@mcap/support";

const decompressHandlers = await loadDecompressHandlers();

function message(channels, m) {
  return [channels.get(m.channelId).topic, m.sequence, m.publishTime.toString(),
          m.logTime.toString(), Buffer.from(m.data).toString("hex")];
}

async function check(path) {
  const bytes = await readFile(path);
  const stream = new McapStreamReader({ decompressHandlers, validateCrcs: true });
  stream.append(bytes);
  const channels = new Map();
  const schemas = {};
  const messages = [];
  let record;
  while ((record = stream.nextRecord()) !== undefined) {
    if (record.type === "Schema") {
      schemas[record.name] = { encoding: record.encoding,
                               data: Buffer.from(record.data).toString("utf8") };
    } else if (record.type === "Channel") {
      channels.set(record.id, record);
    } else if (record.type === "Message") {
      messages.push(message(channels, record));
    }
  }
  const result = {
    done: stream.done(), leftover: stream.bytesRemaining(), messages, schemas,
    channels: [...channels.values()].map((c) => ({ topic: c.topic, encoding: c.messageEncoding,
      metadata: Object.fromEntries(c.metadata) })),
  };
  if (stream.done()) {
    const readable = {
      size: async () => BigInt(bytes.length),
      read: async (offset, size) => bytes.subarray(Number(offset), Number(offset + size)),
    };
    const indexed = await McapIndexedReader.Initialize({ readable, decompressHandlers });
    const byChannel = indexed.channelsById;
    const fromIndex = [];
    for await (const m of indexed.readMessages({ validateCrcs: true })) {
      fromIndex.push(message(byChannel, m));
    }
    result.indexed = { messages: fromIndex.length,
                       statistics: Number(indexed.statistics?.messageCount ?? -1n),
                       chunks: indexed.chunkIndexes.length };
    // the indexed reader yields log-time order: compare as sets of samples
    const key = (m) => m.join(" ");
    const a = messages.map(key).sort();
    const b = fromIndex.map(key).sort();
    if (a.length !== b.length || a.some((k, i) => k !== b[i])) {
      throw new Error("the indexed reader found other messages than the stream reader");
    }
  }
  return result;
}

const results = {};
try {
  for (const path of process.argv.slice(2)) {
    results[path] = await check(path);
  }
} catch (err) {
  console.error(String(err?.stack ?? err));
  process.exit(1);
}
process.stdout.write(JSON.stringify(results));
