// HDoV thesis §5.4 (digest §4): the HDoV-tree file — node pages (the view-invariant parts),
// internal LOD geometry, and the V-data in the three storage schemes (horizontal §5.4.1,
// vertical §5.4.2, indexed-vertical §5.4.3) beside the naive (cell, list-of-objects) lists.
// Byte layout: docs/format.md, "HDoV-tree file".
#include <cmath>

#include "cellwalk/core/error.hpp"
#include "cellwalk/systems/visual/hdov_tree.hpp"
#include "cellwalk/store/mesh_codec.hpp"
#include "core/bytes.hpp"

namespace cellwalk {
namespace {

constexpr uint32_t kVersion = 1;
constexpr uint32_t kNodeHeader = 24;  // height, entry count, LOD count, objects, u64 triangles
constexpr uint32_t kEntryBytes = 28;  // 6 × f32 box, u32 ref
constexpr uint32_t kLodBytes = 16;    // u64 offset, u32 bytes, u32 triangles
constexpr uint32_t kNil = 0xFFFFFFFFu;

constexpr const char* kHeader = "hdov-header";
constexpr const char* kCells = "hdov-cells";
constexpr const char* kNodes = "hdov-nodes";
constexpr const char* kGeometry = "hdov-geometry";
constexpr const char* kNaiveDirectory = "naive-dir";
constexpr const char* kNaiveLists = "naive-lists";

const char* vpage_section(VPageScheme s) {
  switch (s) {
    case VPageScheme::kHorizontal: return "vpages-h";
    case VPageScheme::kVertical: return "vpages-v";
    case VPageScheme::kIndexedVertical: return "vpages-iv";
  }
  return "";
}
const char* index_section(VPageScheme s) { return s == VPageScheme::kVertical ? "vindex-v" : "vindex-iv"; }
constexpr const char* kIvDirectory = "vdir-iv";

void put_vpage(ByteWriter& w, const std::vector<VEntry>& entries, uint32_t max_entries) {
  for (uint32_t e = 0; e < max_entries; ++e) {
    const VEntry v = e < entries.size() ? entries[e] : VEntry{};
    w.put(v.dov);
    w.put(v.nvo);
  }
}

std::vector<uint8_t> encode_node(const HdovNode& node, uint32_t page_size) {
  ByteWriter w;
  w.put(node.height);
  w.put(static_cast<uint32_t>(node.entries.size()));
  w.put(static_cast<uint32_t>(node.lods.size()));
  w.put(node.objects);
  w.put(node.leaf_triangles);
  for (const RTreeEntry& e : node.entries) {
    w.put(e.box.min);
    w.put(e.box.max);
    w.put(e.ref);
  }
  for (const HdovLodRef& l : node.lods) {
    w.put(l.offset);
    w.put(l.bytes);
    w.put(l.triangles);
  }
  if (w.size() > page_size) fail("HDoV-tree", "a node needs " + std::to_string(w.size()) + " bytes, more than a page");
  w.bytes().resize(page_size, 0);
  return std::move(w.bytes());
}

void section(WorldWriter& out, const char* name, std::span<const uint8_t> bytes) {
  out.begin_section(name);
  out.write(bytes);
  out.end_section();
}

// One cell's visible objects and DoVs, ascending ids, from the leaf nodes' V-entries.
std::vector<std::pair<uint32_t, float>> cell_list(const HdovTreeBuild& tree, CellId c) {
  std::vector<std::pair<uint32_t, float>> list;
  for (size_t n = 0; n < tree.nodes.size(); ++n)
    if (tree.nodes[n].leaf() && !tree.vd[c][n].empty())
      for (size_t e = 0; e < tree.nodes[n].entries.size(); ++e)
        if (tree.vd[c][n][e].dov > 0) list.emplace_back(tree.nodes[n].entries[e].ref, tree.vd[c][n][e].dov);
  std::sort(list.begin(), list.end());
  return list;
}

}  // namespace

const char* vpage_scheme_name(VPageScheme scheme) {
  switch (scheme) {
    case VPageScheme::kHorizontal: return "horizontal";
    case VPageScheme::kVertical: return "vertical";
    case VPageScheme::kIndexedVertical: return "indexed-vertical";
  }
  return "?";
}

VPageScheme parse_vpage_scheme(const std::string& name) {
  if (name == "horizontal" || name == "h") return VPageScheme::kHorizontal;
  if (name == "vertical" || name == "v") return VPageScheme::kVertical;
  if (name == "indexed-vertical" || name == "iv") return VPageScheme::kIndexedVertical;
  fail("scheme \"" + name + "\"", "unknown; choose horizontal (h), vertical (v) or indexed-vertical (iv)");
}

std::string default_hdov_path(const std::string& world_path) { return world_path + ".hdov"; }

void write_hdov_tree(const HdovTreeBuild& tree, const std::string& path) {
  const HdovBuildParams& p = tree.params;
  const uint32_t m = p.max_entries, cells = tree.cell_count;
  const auto nodes = static_cast<uint32_t>(tree.nodes.size());
  if (tree.visible_nodes() >= kNil) fail(path, "too many visible nodes for 32-bit V-page pointers");
  uint32_t height = 0;
  if (!tree.nodes.empty()) height = tree.nodes[0].height + 1;
  WorldWriter out(path, p.page_size);

  ByteWriter header;
  for (uint32_t v : {kVersion, p.page_size, m, nodes, cells, height}) header.put(v);
  header.put(tree.object_count);
  header.put(tree.world_triangles);
  header.put(tree.visible_nodes());
  header.put(p.lods.levels);
  header.put(p.lods.ratio);
  header.put(static_cast<uint32_t>(p.lods.min_triangles));
  header.put(static_cast<uint32_t>(p.method));
  section(out, kHeader, header.bytes());
  section(out, kCells, tree.cells);

  out.begin_section(kNodes);
  for (const HdovNode& node : tree.nodes) out.write(encode_node(node, p.page_size));
  out.end_section();
  section(out, kGeometry, tree.geometry);

  // Horizontal: node-major, a V-page reserved for every (node, cell), visible or not.
  out.begin_section(vpage_section(VPageScheme::kHorizontal));
  for (uint32_t n = 0; n < nodes; ++n) {
    ByteWriter w;
    for (uint32_t c = 0; c < cells; ++c) put_vpage(w, tree.vd[c][n], m);
    out.write(w.bytes());
  }
  out.end_section();

  // Vertical and indexed-vertical: each cell's visible nodes' V-pages together, DFS order.
  ByteWriter vpages, vindex, ivindex, ivdir;
  uint32_t next = 0;
  for (uint32_t c = 0; c < cells; ++c) {
    ivdir.put(next);
    uint32_t count = 0;
    for (uint32_t n = 0; n < nodes; ++n) {
      if (tree.vd[c][n].empty()) {
        vindex.put(kNil);
        continue;
      }
      put_vpage(vpages, tree.vd[c][n], m);
      vindex.put(next);
      ivindex.put(n);
      ivindex.put(next);
      ++next;
      ++count;
    }
    ivdir.put(count);
  }
  section(out, vpage_section(VPageScheme::kVertical), vpages.bytes());
  section(out, index_section(VPageScheme::kVertical), vindex.bytes());
  section(out, vpage_section(VPageScheme::kIndexedVertical), vpages.bytes());
  section(out, index_section(VPageScheme::kIndexedVertical), ivindex.bytes());
  section(out, kIvDirectory, ivdir.bytes());

  ByteWriter naive_dir, naive;
  for (uint32_t c = 0; c < cells; ++c) {
    naive_dir.put(static_cast<uint64_t>(naive.size()));
    for (const auto& [object, dov] : cell_list(tree, c)) {
      naive.put(object);
      naive.put(dov);
    }
  }
  naive_dir.put(static_cast<uint64_t>(naive.size()));
  section(out, kNaiveDirectory, naive_dir.bytes());
  section(out, kNaiveLists, naive.bytes());
  out.finish();
}

HdovNode decode_hdov_node(std::span<const uint8_t> page, const std::string& where) {
  ByteReader r(page, where);
  HdovNode node;
  node.height = r.get<uint32_t>("node height");
  const auto count = r.get<uint32_t>("entry count");
  const auto lods = r.get<uint32_t>("LOD count");
  node.objects = r.get<uint32_t>("objects below");
  node.leaf_triangles = r.get<uint64_t>("triangles below");
  if (node.height > 64) r.error("node height " + std::to_string(node.height) + " is implausible");
  if (uint64_t(count) * kEntryBytes + uint64_t(lods) * kLodBytes > r.remaining())
    r.error(std::to_string(count) + " entries and " + std::to_string(lods) + " LODs do not fit the page");
  node.entries.resize(count);
  for (RTreeEntry& e : node.entries) {
    e.box.min = r.get<Vec3>("entry box");
    e.box.max = r.get<Vec3>("entry box");
    e.ref = r.get<uint32_t>("entry ref");
    for (int a = 0; a < 3; ++a)
      if (!std::isfinite(e.box.min[a]) || !std::isfinite(e.box.max[a]) || e.box.min[a] > e.box.max[a])
        r.error("entry box is not finite or inverted");
  }
  node.lods.resize(lods);
  for (HdovLodRef& l : node.lods) {
    l.offset = r.get<uint64_t>("LOD offset");
    l.bytes = r.get<uint32_t>("LOD bytes");
    l.triangles = r.get<uint32_t>("LOD triangles");
  }
  return node;
}

std::vector<VEntry> decode_vpage(std::span<const uint8_t> bytes, uint32_t entries, const std::string& where) {
  ByteReader r(bytes, where);
  if (uint64_t(entries) * 8 > bytes.size()) r.error("a V-page of " + std::to_string(bytes.size()) + " bytes cannot hold " + std::to_string(entries) + " entries");
  std::vector<VEntry> out(entries);
  for (VEntry& v : out) {
    v.dov = r.get<float>("V-entry DoV");
    v.nvo = r.get<uint32_t>("V-entry NVO");
    if (!std::isfinite(v.dov) || v.dov < 0) r.error("V-entry DoV is not a finite value >= 0");
  }
  while (r.remaining() >= 8)
    if (r.get<float>("unused V-entry") != 0 || r.get<uint32_t>("unused V-entry") != 0) r.error("unused V-entry is not zero");
  return out;
}

HdovTree::HdovTree(const World& world, const std::string& path)
    : world_(world), file_(std::make_unique<WorldFile>(path, WorldFile::Options{})) {
  for (const char* s : {kHeader, kCells, kNodes, kGeometry, kNaiveDirectory, kNaiveLists, kIvDirectory, "vpages-h",
                        "vpages-v", "vindex-v", "vpages-iv", "vindex-iv"})
    if (!file_->has_section(s)) fail(path, std::string("has no section ") + s + ": not an HDoV-tree file (run `cellwalk visual-build`)");
  const std::vector<uint8_t> header = file_->read_all(kHeader);
  ByteReader r(header, path + ":" + kHeader);
  if (r.get<uint32_t>("version") != kVersion) r.error("unknown version");
  page_size_ = r.get<uint32_t>("page size");
  max_entries_ = r.get<uint32_t>("M");
  node_count_ = r.get<uint32_t>("node count");
  cell_count_ = r.get<uint32_t>("cell count");
  height_ = r.get<uint32_t>("height");
  const auto objects = r.get<uint64_t>("object count");
  const auto triangles = r.get<uint64_t>("world triangles");
  if (objects != world.object_count() || triangles != world.triangle_count())
    fail(path, "was built from another world than " + world.file().path() + "; delete it and run `cellwalk visual-build` again");
  if (page_size_ != file_->page_size() || max_entries_ < 2 || node_count_ == 0 ||
      kNodeHeader + uint64_t(max_entries_) * kEntryBytes > page_size_)
    r.error("inconsistent page size, M or node count");
  cells_ = deserialize_partition(file_->read_all(kCells), path + ":" + kCells);
  if (cells_->cell_count() != cell_count_) r.error("cell count differs from the partition's");
  const auto expect = [&](const char* s, uint64_t bytes) {
    if (file_->section(s).bytes != bytes) fail(path, std::string("section ") + s + " has the wrong size");
  };
  expect(kNodes, uint64_t(node_count_) * page_size_);
  expect("vpages-h", uint64_t(node_count_) * cell_count_ * vpage_size());
  expect("vindex-v", uint64_t(node_count_) * cell_count_ * 4);
  expect(kIvDirectory, uint64_t(cell_count_) * 8);
  expect(kNaiveDirectory, (uint64_t(cell_count_) + 1) * 8);
  const std::vector<uint8_t> dir = file_->read_all(kIvDirectory);
  ByteReader d(dir, path + ":" + kIvDirectory);
  const uint64_t pairs = file_->section("vindex-iv").bytes / 8;
  for (uint32_t c = 0; c < cell_count_; ++c) {
    const auto first = d.get<uint32_t>("segment start"), count = d.get<uint32_t>("segment length");
    if (uint64_t(first) + count > pairs) d.error("segment past the index");
    iv_directory_.emplace_back(first, count);
  }
  const std::vector<uint8_t> naive = file_->read_all(kNaiveDirectory);
  ByteReader nr(naive, path + ":" + kNaiveDirectory);
  naive_directory_ = nr.get_array<uint64_t>(uint64_t(cell_count_) + 1, "list offsets");
  for (size_t c = 0; c + 1 < naive_directory_.size(); ++c)
    if (naive_directory_[c] > naive_directory_[c + 1] || naive_directory_[c + 1] > file_->section(kNaiveLists).bytes ||
        (naive_directory_[c + 1] - naive_directory_[c]) % 8 != 0)
      nr.error("list offsets out of order or past the lists");
}

HdovTree::~HdovTree() = default;

SchemeStorage HdovTree::storage(VPageScheme scheme) const {
  SchemeStorage s{.vpage_bytes = file_->section(vpage_section(scheme)).bytes};
  if (scheme != VPageScheme::kHorizontal) s.index_bytes = file_->section(index_section(scheme)).bytes;
  if (scheme == VPageScheme::kIndexedVertical) s.directory_bytes = file_->section(kIvDirectory).bytes;
  return s;
}

uint64_t HdovTree::naive_bytes() const {
  return file_->section(kNaiveDirectory).bytes + file_->section(kNaiveLists).bytes;
}

HdovNode HdovTree::read_node(uint32_t node) const {
  const std::string where = file_->path() + ":node " + std::to_string(node);
  if (node >= node_count_) fail(where, "no such node");
  HdovNode n = decode_hdov_node(file_->read(file_->section(kNodes), uint64_t(node) * page_size_, page_size_), where);
  const uint64_t geometry = file_->section(kGeometry).bytes;
  if (n.entries.size() > max_entries_) fail(where, "more entries than M");
  for (const RTreeEntry& e : n.entries)
    if (n.leaf() ? e.ref >= world_.object_count() : (e.ref <= node || e.ref >= node_count_))
      fail(where, "entry ref " + std::to_string(e.ref) + " out of range");
  for (const HdovLodRef& l : n.lods)
    if (l.offset > geometry || l.bytes > geometry - l.offset) fail(where, "LOD past the geometry section");
  return n;
}

std::vector<VEntry> HdovTree::read_vpage(VPageScheme scheme, uint64_t offset, uint32_t entries) const {
  const SectionInfo& s = file_->section(vpage_section(scheme));
  const std::string where = file_->path() + ":" + s.name + "@" + std::to_string(offset);
  if (offset > s.bytes || vpage_size() > s.bytes - offset) fail(where, "V-page past the section");
  return decode_vpage(file_->read(s, offset, vpage_size()), entries, where);
}

std::vector<uint8_t> HdovTree::read_bytes(const char* name, uint64_t offset, uint64_t length) const {
  const SectionInfo& s = file_->section(name);
  if (offset > s.bytes || length > s.bytes - offset) fail(file_->path() + ":" + name, "read past the section");
  return length == 0 ? std::vector<uint8_t>{} : file_->read(s, offset, length);
}

Mesh HdovTree::read_lod(const HdovLodRef& lod) const {
  return decode_mesh(read_bytes(kGeometry, lod.offset, lod.bytes), file_->path() + ":" + kGeometry);
}

uint64_t HdovTree::resident_bytes() const {
  return sizeof(*this) + file_->resident_bytes() + iv_directory_.size() * 8 + naive_directory_.size() * 8 +
         cells_->cell_count() * sizeof(ViewCell);
}

}  // namespace cellwalk
