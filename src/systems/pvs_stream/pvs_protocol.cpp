// Seed 004 (Zheng), §7.3 over TCP: the PVS streaming messages (docs/protocol.md).
#include "cellwalk/systems/pvs_stream/pvs_protocol.hpp"

#include <algorithm>

#include "cellwalk/net/frame.hpp"
#include "core/bytes.hpp"
#include "net/message_parse.hpp"

namespace cellwalk::pvs_stream {

static_assert(sizeof(CatalogEntry) == 28, "a catalog entry is 28 bytes on the wire (docs/protocol.md)");

namespace {

using net::ProtocolError;

using net::expect_end;
using net::parsing;

std::vector<uint32_t> get_ids(ByteReader& r, const char* what, uint32_t most, uint32_t below) {
  const uint32_t n = r.get<uint32_t>(what);
  if (n > most) throw ProtocolError(std::string(what) + ": " + std::to_string(n) + " ids, more than the " + std::to_string(most) + " allowed");
  std::vector<uint32_t> ids = r.get_array<uint32_t>(n, what);
  for (uint32_t id : ids)
    if (id >= below) throw ProtocolError(std::string(what) + ": id " + std::to_string(id) + " is not below " + std::to_string(below));
  return ids;
}

void put_ids(ByteWriter& w, const std::vector<uint32_t>& ids) {
  w.put(uint32_t(ids.size()));
  w.put_array(std::span<const uint32_t>(ids));
}

}  // namespace

std::vector<uint8_t> encode_hello() {
  ByteWriter w;
  w.put(kPvsProtocolVersion);
  return std::move(w.bytes());
}

void parse_hello(std::span<const uint8_t> payload) {
  parsing("hello", [&] {
    ByteReader r(payload, "hello");
    const uint32_t version = r.get<uint32_t>("version");
    expect_end(r, "hello");
    if (version != kPvsProtocolVersion)
      throw ProtocolError("PVS protocol version " + std::to_string(version) + ", this server speaks " + std::to_string(kPvsProtocolVersion));
    return 0;
  });
}

std::vector<uint8_t> encode_welcome(const Welcome& x) {
  ByteWriter w;
  w.put(x.world_bytes);
  w.put(x.objects);
  w.put(x.cell_count);
  w.put(x.origin_x);
  w.put(x.origin_z);
  w.put(x.cell_size);
  w.put(x.rows);
  w.put(x.cols);
  w.put_array(std::span<const uint32_t>(x.cells));
  return std::move(w.bytes());
}

Welcome parse_welcome(std::span<const uint8_t> payload) {
  return parsing("welcome", [&] {
    ByteReader r(payload, "welcome");
    Welcome x;
    x.world_bytes = r.get<uint64_t>("world bytes");
    x.objects = r.get<uint32_t>("objects");
    x.cell_count = r.get<uint32_t>("cell count");
    x.origin_x = r.get<double>("origin x");
    x.origin_z = r.get<double>("origin z");
    x.cell_size = r.get<double>("cell size");
    x.rows = r.get<uint32_t>("rows");
    x.cols = r.get<uint32_t>("cols");
    if (!(x.cell_size > 0) || x.rows == 0 || x.cols == 0) throw ProtocolError("a welcome with an empty grid");
    x.cells = r.get_array<uint32_t>(uint64_t(x.rows) * x.cols, "cells");
    for (uint32_t c : x.cells)
      if (c != kNoCell && c >= x.cell_count) throw ProtocolError("a welcome naming cell " + std::to_string(c) + " of " + std::to_string(x.cell_count));
    expect_end(r, "welcome");
    return x;
  });
}

std::vector<uint8_t> encode_fetch(const FetchRequest& f) {
  ByteWriter w;
  w.put(f.sequence);
  w.put(f.level);
  put_ids(w, f.cells);
  put_ids(w, f.dropped);
  return std::move(w.bytes());
}

FetchRequest parse_fetch(std::span<const uint8_t> payload, uint32_t cell_count, uint32_t object_count) {
  return parsing("fetch", [&] {
    ByteReader r(payload, "fetch");
    FetchRequest f;
    f.sequence = r.get<uint32_t>("sequence");
    f.level = r.get<uint32_t>("level");
    f.cells = get_ids(r, "fetch cells", kMaxCellsPerFetch, cell_count);
    f.dropped = get_ids(r, "fetch dropped objects", object_count, object_count);
    expect_end(r, "fetch");
    return f;
  });
}

std::vector<uint8_t> encode_rows(const RowsReply& x) {
  ByteWriter w;
  w.put(x.sequence);
  w.put(uint32_t(x.rows.size()));
  for (const auto& [cell, ids] : x.rows) {
    w.put(cell);
    put_ids(w, ids);
  }
  return std::move(w.bytes());
}

RowsReply parse_rows(std::span<const uint8_t> payload) {
  return parsing("rows", [&] {
    ByteReader r(payload, "rows");
    RowsReply x;
    x.sequence = r.get<uint32_t>("sequence");
    const uint32_t n = r.get<uint32_t>("row count");
    if (n > kMaxCellsPerFetch) throw ProtocolError("rows: " + std::to_string(n) + " rows in one reply");
    for (uint32_t i = 0; i < n; ++i) {
      const uint32_t cell = r.get<uint32_t>("cell");
      std::vector<uint32_t> ids = get_ids(r, "row", 0xFFFFFFFFu, 0xFFFFFFFFu);
      if (!std::is_sorted(ids.begin(), ids.end())) throw ProtocolError("rows: a row is not sorted");
      x.rows.emplace_back(cell, std::move(ids));
    }
    expect_end(r, "rows");
    return x;
  });
}

std::vector<uint8_t> encode_object(const ObjectReply& o) {
  ByteWriter w;
  w.put(o.sequence);
  w.put(o.id);
  w.put(o.level);
  w.put(uint32_t(o.bytes.size()));
  w.put_array(std::span<const uint8_t>(o.bytes));
  return std::move(w.bytes());
}

ObjectReply parse_object(std::span<const uint8_t> payload) {
  return parsing("object", [&] {
    ByteReader r(payload, "object");
    ObjectReply o;
    o.sequence = r.get<uint32_t>("sequence");
    o.id = r.get<uint32_t>("id");
    o.level = r.get<uint32_t>("level");
    o.bytes = r.get_array<uint8_t>(r.get<uint32_t>("byte count"), "bytes");
    expect_end(r, "object");
    return o;
  });
}

std::vector<uint8_t> encode_done(const DoneReply& d) {
  ByteWriter w;
  w.put(d.sequence);
  w.put(d.objects);
  return std::move(w.bytes());
}

DoneReply parse_done(std::span<const uint8_t> payload) {
  return parsing("done", [&] {
    ByteReader r(payload, "done");
    DoneReply d;
    d.sequence = r.get<uint32_t>("sequence");
    d.objects = r.get<uint32_t>("objects");
    expect_end(r, "done");
    return d;
  });
}

void parse_catalog_request(std::span<const uint8_t> payload) {
  if (!payload.empty()) throw ProtocolError("a catalog request with " + std::to_string(payload.size()) + " bytes; it is empty");
}

std::vector<uint8_t> encode_catalog(const Catalog& c) {
  ByteWriter w;
  w.put(uint32_t(c.objects.size()));
  w.put_array(std::span<const CatalogEntry>(c.objects));
  return std::move(w.bytes());
}

Catalog parse_catalog(std::span<const uint8_t> payload) {
  return parsing("catalog", [&] {
    ByteReader r(payload, "catalog");
    Catalog c;
    c.objects = r.get_array<CatalogEntry>(r.get<uint32_t>("object count"), "objects");
    expect_end(r, "catalog");
    return c;
  });
}

std::vector<uint8_t> encode_error(const std::string& reason) {
  ByteWriter w;
  w.put_string(reason.substr(0, 1000));
  return std::move(w.bytes());
}

std::string parse_error(std::span<const uint8_t> payload) {
  return parsing("error", [&] {
    ByteReader r(payload, "error");
    std::string s = r.get_string("reason");
    expect_end(r, "error");
    return s;
  });
}

}  // namespace cellwalk::pvs_stream
