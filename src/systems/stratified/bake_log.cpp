// Resumable, sharded far-field baking: bake_log.hpp says what and why.
#include "cellwalk/systems/stratified/bake_log.hpp"

#include <xxhash.h>

#include <cstring>
#include <filesystem>
#include <fstream>

#include "cellwalk/core/error.hpp"
#include "core/bytes.hpp"
#include "store/checkpoint_file.hpp"

namespace cellwalk::stratified {
namespace {

// '2': records hold 8-bit depth (farfield version 2); a file of '1' is refused, or discarded as
// a checkpoint.
constexpr char kMagic[8] = {'C', 'W', 'S', 'T', 'R', 'B', 'K', '2'};
constexpr uint64_t kHeaderBytes = 8 + 8 + 4 + 4 + 8;  // magic, run hash, shard, shards, header checksum

std::vector<uint8_t> header(uint64_t hash, int shard, int shards) {
  ByteWriter w;
  w.put_array(std::span<const char>(kMagic, 8));
  w.put(hash);
  w.put(uint32_t(shard));
  w.put(uint32_t(shards));
  w.put(XXH3_64bits(w.bytes().data(), w.size()));
  return std::move(w.bytes());
}

}  // namespace

uint64_t bake_run_hash(const World& world, const Viewcells& cells, const StratifiedParams& params, const BakeSettings& bake) {
  ByteWriter w;
  w.put(uint64_t(world.object_count()));
  const std::vector<uint8_t> objects = world.file().read_all("objects");
  w.put(XXH3_64bits(objects.data(), objects.size()));
  w.put(params.alpha);
  w.put(params.v);
  w.put(params.b);
  w.put_string(params.sizing);
  w.put(int32_t(params.resolution));
  w.put(int32_t(bake.resolution));
  w.put(bake.max_texels);
  const ViewCellPartition& partition = *cells.partition;
  w.put(uint64_t(partition.cell_count()));
  for (CellId c = 0; c < partition.cell_count(); ++c) {
    const ViewCell& cell = partition.cell(c);
    w.put(cell.box.min);
    w.put(cell.box.max);
    w.put(uint8_t(cell.computed()));
  }
  return XXH3_64bits(w.bytes().data(), w.size());
}

BakePart::BakePart(const std::string& path) : path_(path) {
  const std::vector<uint8_t> bytes = read_checkpoint_file(path);
  ByteReader r(bytes, path);
  if (r.get_array<char>(8, "magic") != std::vector<char>(kMagic, kMagic + 8))
    r.error("not a stratify part or checkpoint of this cellwalk (bad magic): give the files this version's "
            "`stratify build --shard` wrote");
  hash_ = r.get<uint64_t>("run hash");
  shard_ = int(r.get<uint32_t>("shard"));
  shards_ = int(r.get<uint32_t>("shards"));
  const uint64_t header_end = r.offset();
  if (r.get<uint64_t>("header checksum") != XXH3_64bits(bytes.data(), header_end)) r.error("header checksum mismatch");
  if (shards_ < 1 || shard_ >= shards_) r.error("shard " + std::to_string(shard_) + " of " + std::to_string(shards_) + " is no shard");
  valid_bytes_ = r.offset();
  while (true) {
    const uint64_t start = r.offset();
    const std::optional<std::vector<uint8_t>> record = next_framed_record(r);
    if (!record || record->size() < 4) break;
    uint32_t cell = 0;
    std::memcpy(&cell, record->data(), 4);
    records_[cell] = {start + 12 + 4, uint32_t(record->size() - 4)};
    valid_bytes_ = r.offset();
  }
}

std::vector<CellId> BakePart::cells() const {
  std::vector<CellId> out;
  for (const auto& [cell, where] : records_) out.push_back(cell);
  return out;
}

std::vector<uint8_t> BakePart::record(CellId cell, float b, int resolution, uint64_t object_count) const {
  std::vector<uint8_t> bytes = read_record(cell);
  decode_far_field(bytes, b, resolution, object_count, path_ + "@" + std::to_string(records_.at(cell).first));
  return bytes;
}

CellFarField BakePart::far_field(CellId cell, float b, int resolution, uint64_t object_count) const {
  return decode_far_field(read_record(cell), b, resolution, object_count, path_ + "@" + std::to_string(records_.at(cell).first));
}

std::vector<uint8_t> BakePart::read_record(CellId cell) const {
  const auto& [offset, length] = records_.at(cell);
  std::ifstream in(path_, std::ios::binary);
  std::vector<uint8_t> bytes(length);
  in.seekg(std::streamoff(offset));
  if (!in.read(reinterpret_cast<char*>(bytes.data()), std::streamsize(length)))
    fail(path_ + "@" + std::to_string(offset), "cannot read the record of cell " + std::to_string(cell) +
                                                   ": the file changed while it was used; bake the shard again");
  return bytes;
}

struct BakeLog::Writer {
  Writer(const std::string& path, uint64_t keep, std::span<const uint8_t> header) : file(path, keep, header) {}
  CheckpointWriter file;
};

BakeLog::BakeLog(const std::string& path, uint64_t hash, int shard, int shards) {
  if (std::filesystem::exists(path)) {
    try {
      part_ = BakePart(path);
    } catch (const Error& e) {
      warn(e.what(), "the checkpoint's header is unreadable, so it is discarded and every cell is baked again");
      part_ = BakePart();
    }
    if (part_.valid_bytes_ > 0 && (part_.hash_ != hash || part_.shard_ != shard || part_.shards_ != shards))
      fail(path, "belongs to a different bake (world, cells, α, box, resolution, levels or shard); delete it to start over");
  }
  part_.path_ = path;
  part_.hash_ = hash;
  part_.shard_ = shard;
  part_.shards_ = shards;
  resumed_ = part_.records_.size();
  end_ = part_.valid_bytes_ ? part_.valid_bytes_ : kHeaderBytes;
  writer_ = std::make_unique<Writer>(path, part_.valid_bytes_, header(hash, shard, shards));
}

BakeLog::~BakeLog() = default;

void BakeLog::append(CellId cell, std::span<const uint8_t> record) {
  std::vector<uint8_t> payload(4);
  const uint32_t id = cell;
  std::memcpy(payload.data(), &id, 4);
  payload.insert(payload.end(), record.begin(), record.end());
  std::vector<uint8_t> framed;
  append_framed_record(framed, payload);
  writer_->file.write_all(framed);
  part_.index(cell, end_ + 12 + 4, uint32_t(record.size()));
  end_ += framed.size();
}

}  // namespace cellwalk::stratified
