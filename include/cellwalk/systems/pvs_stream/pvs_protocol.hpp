// The PVS streaming protocol (seed 004, §7.3's delta transmission over TCP; docs/protocol.md,
// "PVS streaming"): the messages and their parsers. Every parser checks counts against the
// bytes left and ids against the world before allocating, and throws net::ProtocolError.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace cellwalk::pvs_stream {

enum class PvsMessage : uint8_t {
  hello = 1, welcome = 2, fetch = 3, rows = 4, object = 5, done = 6, error = 7, catalog_request = 8, catalog = 9
};
constexpr uint32_t kPvsProtocolVersion = 1;
constexpr uint32_t kNoCell = 0xFFFFFFFFu;
constexpr uint32_t kMaxCellsPerFetch = 64;

// Server → client, once: the world and its grid of view cells. cells[row * cols + col] is the
// cell id there, kNoCell where there is none (solid, skipped, or outside).
struct Welcome {
  uint64_t world_bytes = 0;  // the world file's size: a client can tell two worlds apart
  uint32_t objects = 0, cell_count = 0;
  double origin_x = 0, origin_z = 0, cell_size = 0;
  uint32_t rows = 0, cols = 0;
  std::vector<uint32_t> cells;
};

// Client → server: the rows of `cells` and the geometry the client lacks. `dropped`: the objects
// it deleted since its last fetch (§7.4's ΔS_d), so the server's mirror of what it holds stays
// true and the reply is ΔS = S_J − S_I in one round trip.
struct FetchRequest {
  uint32_t sequence = 0;
  uint32_t level = 0;  // the level of detail wanted (the coarsest an object has, if it has fewer)
  std::vector<uint32_t> cells, dropped;
};

struct RowsReply {
  uint32_t sequence = 0;
  std::vector<std::pair<uint32_t, std::vector<uint32_t>>> rows;  // (cell, sorted object ids)
};

struct ObjectReply {
  uint32_t sequence = 0, id = 0, level = 0;
  std::vector<uint8_t> bytes;  // the level as the world file encodes it
};

struct DoneReply {
  uint32_t sequence = 0, objects = 0;
};

// Server → client, when asked (catalog_request, an empty message, any time after the hello):
// what a client that has no world file needs to draw and cull an object before and after its
// geometry comes (the browser client). objects[id] for every id of the world.
struct CatalogEntry {
  uint32_t color = 0;     // RGBA8, r in the low byte: used where the mesh has no vertex colours
  float box[6] = {};      // min x y z, max x y z
};
struct Catalog {
  std::vector<CatalogEntry> objects;
};

std::vector<uint8_t> encode_hello();
void parse_hello(std::span<const uint8_t> payload);  // throws for another version
std::vector<uint8_t> encode_welcome(const Welcome& w);
Welcome parse_welcome(std::span<const uint8_t> payload);
std::vector<uint8_t> encode_fetch(const FetchRequest& f);
// REQUIRES nothing of the bytes; ids are checked against cell_count and object_count.
FetchRequest parse_fetch(std::span<const uint8_t> payload, uint32_t cell_count, uint32_t object_count);
std::vector<uint8_t> encode_rows(const RowsReply& r);
RowsReply parse_rows(std::span<const uint8_t> payload);
std::vector<uint8_t> encode_object(const ObjectReply& o);
ObjectReply parse_object(std::span<const uint8_t> payload);
std::vector<uint8_t> encode_done(const DoneReply& d);
DoneReply parse_done(std::span<const uint8_t> payload);
void parse_catalog_request(std::span<const uint8_t> payload);  // throws unless empty
std::vector<uint8_t> encode_catalog(const Catalog& c);
Catalog parse_catalog(std::span<const uint8_t> payload);
std::vector<uint8_t> encode_error(const std::string& reason);
std::string parse_error(std::span<const uint8_t> payload);

}  // namespace cellwalk::pvs_stream
