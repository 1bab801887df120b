// CAE-RLSM map files: the whole provenance tree as YAML (format documented in README.md).
// Saving writes a temporary file, fsyncs it and renames it over the target; loading parses and
// validates into a fresh state and only then replaces the current one.
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>
#include <unordered_set>

#include "line_map_merging/mergers/cae_rlsm.hpp"
#include "linemap/atomic_file.hpp"

namespace line_map_merging
{
namespace
{
// 2: parameters gained 'weighting', 'map_merge' and 'regroup_on_adjust'. 3: 'absorb_contained'.
// 4: a keyframe entry may carry its session (a 9th number). Older files still load (see load()).
constexpr int kFormatVersion = 4;
constexpr int kOldestFormatVersion = 1;

std::string where(const std::string& path, const YAML::Node& node, const std::string& field)
{
  std::string s = "map file '" + path + "'";
  if (node.Mark().line >= 0) s += " line " + std::to_string(node.Mark().line + 1);
  return s + ": field '" + field + "'";
}

const YAML::Node require(const std::string& path, const YAML::Node& parent, const std::string& field)
{
  // Indexing a scalar or a sequence by name throws a YAML exception, not a MapFileError.
  if (!parent.IsMap())
    throw MapFileError(where(path, parent, field) + " is missing (its parent is not a mapping)");
  const YAML::Node n = parent[field];
  if (!n) throw MapFileError(where(path, parent, field) + " is missing");
  return n;
}

template <typename T>
T read(const std::string& path, const YAML::Node& node, const std::string& field)
{
  try
  {
    return node.as<T>();
  }
  catch (const YAML::Exception&)
  {
    throw MapFileError(where(path, node, field) + ": '" +
                       (node.IsScalar() ? node.Scalar() : "<not a scalar>") + "' is not a valid value");
  }
}

double readFinite(const std::string& path, const YAML::Node& node, const std::string& field)
{
  const double v = read<double>(path, node, field);
  if (!std::isfinite(v)) throw MapFileError(where(path, node, field) + " is not finite");
  return v;
}

std::vector<double> readNumbers(const std::string& path, const YAML::Node& node, const std::string& field,
                                std::size_t count)
{
  if (!node.IsSequence() || node.size() != count)
    throw MapFileError(where(path, node, field) + " must be a list of " + std::to_string(count) + " numbers");
  std::vector<double> v(count);
  for (std::size_t i = 0; i < count; ++i) v[i] = readFinite(path, node[i], field);
  return v;
}

void emitNumbers(YAML::Emitter& out, std::initializer_list<double> values)
{
  out << YAML::Flow << YAML::BeginSeq;
  for (double v : values) out << v;
  out << YAML::EndSeq;
}

/// The file's YAML, checked to be a whole map file of a version this build reads, by `method`.
/// `path` names the map's origin in messages: a file, or a session file's record.
YAML::Node parseMapText(const std::string& text, const std::string& path, const std::string& method)
{
  YAML::Node root;
  try
  {
    root = YAML::Load(text);
  }
  catch (const YAML::Exception& e)
  {
    throw MapFileError("map file '" + path + "' line " + std::to_string(e.mark.line + 1) +
                       ": not valid YAML: " + e.msg);
  }
  if (!root.IsMap())
    throw MapFileError("map file '" + path + "': not a line map file (no top-level mapping)");
  const int version = read<int>(path, require(path, root, "format_version"), "format_version");
  if (version < kOldestFormatVersion || version > kFormatVersion)
    throw MapFileError("map file '" + path + "': format_version " + std::to_string(version) +
                       " is not supported (this build reads " + std::to_string(kOldestFormatVersion) +
                       " to " + std::to_string(kFormatVersion) + ")");
  const std::string found = read<std::string>(path, require(path, root, "method"), "method");
  if (found != method)
    throw MapFileError("map file '" + path + "': field 'method' is '" + found + "', expected '" + method +
                       "'");
  if (!require(path, root, "end_of_map").as<bool>(false))
    throw MapFileError("map file '" + path + "': field 'end_of_map' is not true (truncated file?)");
  return root;
}

/// `params` with the file's fusion and adjustment parameters (block `p`).
CaeParams readParams(const std::string& path, const YAML::Node& p, CaeParams params)
{
  params.fusion.max_angle = readFinite(path, require(path, p, "max_angle"), "parameters/max_angle");
  params.fusion.max_distance = readFinite(path, require(path, p, "max_distance"), "parameters/max_distance");
  params.fusion.min_overlap = readFinite(path, require(path, p, "min_overlap"), "parameters/min_overlap");
  params.consistent_adjustment =
      read<bool>(path, require(path, p, "consistent_adjustment"), "parameters/consistent_adjustment");
  // Version 1 files were made with the paper's count weighting, no map-level merge and no regrouping:
  // they load as such, so a saved map adjusts as it would have.
  const std::string weighting =
      p["weighting"] ? read<std::string>(path, p["weighting"], "parameters/weighting") : std::string("count");
  if (weighting != "length" && weighting != "count")
    throw MapFileError("map file '" + path + "': field 'parameters/weighting' is '" + weighting +
                       "', expected 'length' or 'count'");
  params.fusion.weighting = weighting == "length" ? FusionWeighting::length : FusionWeighting::count;
  params.map_merge = p["map_merge"] ? read<bool>(path, p["map_merge"], "parameters/map_merge") : false;
  // Files written before absorb_contained existed merged by the fusion conditions alone.
  params.absorb_contained =
      p["absorb_contained"] ? read<bool>(path, p["absorb_contained"], "parameters/absorb_contained") : false;
  params.regroup_on_adjust = p["regroup_on_adjust"]
                                 ? read<bool>(path, p["regroup_on_adjust"], "parameters/regroup_on_adjust")
                                 : false;
  try
  {
    params.fusion.validate();
  }
  catch (const std::exception& e)
  {
    throw MapFileError("map file '" + path + "': " + e.what());
  }
  return params;
}

/// The parameters a map file records: those that shape how a loaded map goes on adjusting.
void emitParams(YAML::Emitter& out, const CaeParams& params)
{
  out << YAML::BeginMap;
  out << YAML::Key << "max_angle" << YAML::Value << params.fusion.max_angle;
  out << YAML::Key << "max_distance" << YAML::Value << params.fusion.max_distance;
  out << YAML::Key << "min_overlap" << YAML::Value << params.fusion.min_overlap;
  out << YAML::Key << "consistent_adjustment" << YAML::Value << params.consistent_adjustment;
  out << YAML::Key << "weighting" << YAML::Value
      << (params.fusion.weighting == FusionWeighting::length ? "length" : "count");
  out << YAML::Key << "map_merge" << YAML::Value << params.map_merge;
  out << YAML::Key << "absorb_contained" << YAML::Value << params.absorb_contained;
  out << YAML::Key << "regroup_on_adjust" << YAML::Value << params.regroup_on_adjust;
  out << YAML::EndMap;
}

}  // namespace

void CaeRlsm::save(const std::string& path) const
{
  const std::string text = mapText();
  try
  {
    linemap::writeFileAtomically(path, text, "map file");
  }
  catch (const std::runtime_error& e)
  {
    throw MapFileError(e.what());
  }
}

std::string CaeRlsm::mapText() const
{
  YAML::Emitter out;
  out.SetDoublePrecision(17);  // round-trips every double exactly
  out << YAML::BeginMap;
  out << YAML::Key << "format_version" << YAML::Value << kFormatVersion;
  out << YAML::Key << "method" << YAML::Value << name();
  out << YAML::Key << "parameters" << YAML::Value;
  emitParams(out, params_);
  out << YAML::Key << "next_id" << YAML::Value << next_id_;
  out << YAML::Key << "keyframe_count" << YAML::Value << keyframes_.size();
  out << YAML::Key << "segment_count" << YAML::Value << nodes_.size();
  out << YAML::Key << "leaf_count" << YAML::Value << leaves_.size();

  out << YAML::Key << "keyframes" << YAML::Value << YAML::BeginSeq;
  for (const KeyframeInfo& k : keyframes())
  {
    out << YAML::Flow << YAML::BeginSeq << k.index << k.stamp << k.pose.x << k.pose.y << k.pose.theta
        << k.mount.x << k.mount.y << k.mount.theta;
    if (k.session > 0) out << k.session;  // a map of one session is written as before sessions existed
    out << YAML::EndSeq;
  }
  out << YAML::EndSeq;

  emitSegments(out);
  out << YAML::Key << "end_of_map" << YAML::Value << true;  // a file cut at a line boundary lacks it
  out << YAML::EndMap;
  if (!out.good()) throw MapFileError("map file: cannot encode: " + out.GetLastError());
  return std::string(out.c_str()) + "\n";
}

void CaeRlsm::emitSegments(YAML::Emitter& out) const
{
  // Every node, the ones map() withholds (single_view_min_length) included: the file is the whole state.
  std::vector<std::uint64_t> ids;
  ids.reserve(nodes_.size());
  for (const auto& entry : nodes_) ids.push_back(entry.first);
  std::sort(ids.begin(), ids.end());
  out << YAML::Key << "segments" << YAML::Value << YAML::BeginSeq;
  for (std::uint64_t id : ids)
  {
    const Segment2& segment = nodes_.at(id).segment;
    out << YAML::BeginMap;
    out << YAML::Key << "id" << YAML::Value << id;
    // For readers of the file: map() does not show it yet. Derived from the leaves, so load ignores it.
    if (!shown(nodes_.at(id))) out << YAML::Key << "withheld" << YAML::Value << true;
    out << YAML::Key << "segment" << YAML::Value;
    emitNumbers(out, {segment.start.x(), segment.start.y(), segment.end.x(), segment.end.y()});
    out << YAML::Key << "leaves" << YAML::Value << YAML::BeginSeq;
    for (std::uint32_t l : nodes_.at(id).leaves)
    {
      const LeafRecord& leaf = leaves_[l];
      out << YAML::Flow << YAML::BeginSeq << keyframes_[leaf.slot].index << leaf.local.start.x()
          << leaf.local.start.y() << leaf.local.end.x() << leaf.local.end.y() << YAML::EndSeq;
    }
    out << YAML::EndSeq << YAML::EndMap;
  }
  out << YAML::EndSeq;
}

void CaeRlsm::load(const std::string& path)
{
  std::string text;
  try
  {
    text = linemap::readWholeFile(path, "map file");
  }
  catch (const std::runtime_error& e)
  {
    throw MapFileError(e.what());
  }
  loadText(text, path);
}

void CaeRlsm::loadText(const std::string& text, const std::string& path)
{
  const YAML::Node root = parseMapText(text, path, name());
  CaeRlsm fresh(readParams(path, require(path, root, "parameters"), params_));
  fresh.next_id_ = read<std::uint64_t>(path, require(path, root, "next_id"), "next_id");
  fresh.loadKeyframes(path, root);
  fresh.loadSegments(path, root);
  fresh.sortLeavesByKeyframe();
  fresh.rebuildIndex();
  // Everything parsed and checked: take it over (threads and spatial_index stay as configured).
  *this = std::move(fresh);
}

void CaeRlsm::loadKeyframes(const std::string& path, const YAML::Node& root)
{
  const auto keyframe_count =
      read<std::size_t>(path, require(path, root, "keyframe_count"), "keyframe_count");
  const YAML::Node keyframes = require(path, root, "keyframes");
  if (!keyframes.IsSequence() || keyframes.size() != keyframe_count)
    throw MapFileError(where(path, keyframes, "keyframes") +
                       " must list keyframe_count = " + std::to_string(keyframe_count) + " keyframes");
  for (const YAML::Node& k : keyframes)
  {
    if (!k.IsSequence() || (k.size() != 8 && k.size() != 9))
      throw MapFileError(where(path, k, "keyframes") +
                         " entries must be [index, stamp, x, y, theta, mount_x, mount_y, mount_theta, "
                         "session (optional)]");
    const auto index = read<std::uint64_t>(path, k[0], "keyframes/index");
    const std::vector<double> v = readNumbers(path, k, "keyframes", k.size());
    const std::uint32_t session = k.size() == 9 ? read<std::uint32_t>(path, k[8], "keyframes/session") : 0;
    if (slot_of_.count(index))
      throw MapFileError(where(path, k, "keyframes") + ": keyframe index " + std::to_string(index) +
                         " repeated");
    slot_of_.emplace(index, static_cast<std::uint32_t>(keyframes_.size()));
    keyframes_.push_back({index, v[1], {v[2], v[3], v[4]}, {v[5], v[6], v[7]}});
    keyframes_.back().session = session;
    // Keyframes merged after this load belong to a later session.
    session_ = std::max(session_, session + 1);
  }
  updateTransforms();
}

void CaeRlsm::loadSegments(const std::string& path, const YAML::Node& root)
{
  const auto segment_count = read<std::size_t>(path, require(path, root, "segment_count"), "segment_count");
  const auto leaf_count = read<std::size_t>(path, require(path, root, "leaf_count"), "leaf_count");
  const YAML::Node segments = require(path, root, "segments");
  if (!segments.IsSequence() || segments.size() != segment_count)
    throw MapFileError(where(path, segments, "segments") +
                       " must list segment_count = " + std::to_string(segment_count) + " segments");
  for (const YAML::Node& s : segments)
  {
    if (!s.IsMap()) throw MapFileError(where(path, s, "segments") + " entries must be mappings");
    const auto id = read<std::uint64_t>(path, require(path, s, "id"), "segments/id");
    if (id >= next_id_)
      throw MapFileError(where(path, s, "segments/id") + ": id " + std::to_string(id) +
                         " is not below next_id");
    if (nodes_.count(id))
      throw MapFileError(where(path, s, "segments/id") + ": id " + std::to_string(id) + " repeated");
    const std::vector<double> e = readNumbers(path, require(path, s, "segment"), "segments/segment", 4);
    const YAML::Node leaves = require(path, s, "leaves");
    if (!leaves.IsSequence() || leaves.size() == 0)
      throw MapFileError(where(path, leaves, "segments/leaves") + " must be a non-empty list");
    Node node;
    node.segment = Segment2(Vec2(e[0], e[1]), Vec2(e[2], e[3]));
    for (const YAML::Node& l : leaves)
    {
      node.leaves.push_back(static_cast<std::uint32_t>(leaves_.size()));
      leaves_.push_back(readLeaf(path, l));
    }
    for (std::uint32_t l : node.leaves) node.moments.add(worldLeaf(l));
    nodes_.emplace(id, std::move(node));
  }
  if (leaves_.size() != leaf_count)
    throw MapFileError("map file '" + path + "': " + std::to_string(leaves_.size()) +
                       " leaves found, field 'leaf_count' says " + std::to_string(leaf_count));
}

CaeRlsm::LeafRecord CaeRlsm::readLeaf(const std::string& path, const YAML::Node& l) const
{
  if (!l.IsSequence() || l.size() != 5)
    throw MapFileError(where(path, l, "segments/leaves") + " entries must be [keyframe, sx, sy, ex, ey]");
  const auto keyframe = read<std::uint64_t>(path, l[0], "segments/leaves/keyframe");
  const auto slot = slot_of_.find(keyframe);
  if (slot == slot_of_.end())
    throw MapFileError(where(path, l, "segments/leaves") + ": keyframe " + std::to_string(keyframe) +
                       " is not in 'keyframes'");
  const std::vector<double> v = readNumbers(path, l, "segments/leaves", 5);
  const Segment2 local(Vec2(v[1], v[2]), Vec2(v[3], v[4]));
  if (!isValidSegment(local)) throw MapFileError(where(path, l, "segments/leaves") + ": zero-length segment");
  return {slot->second, local};
}

void CaeRlsm::sortLeavesByKeyframe()
{
  // The file lists the leaves by segment; regrouping replays them keyframe by keyframe in arrival order
  // (the crossing resolution after each keyframe depends on it), so they are put back in keyframe order.
  std::vector<std::uint32_t> order(leaves_.size());
  for (std::uint32_t l = 0; l < order.size(); ++l) order[l] = l;
  std::stable_sort(order.begin(), order.end(),
                   [&](std::uint32_t a, std::uint32_t b) { return leaves_[a].slot < leaves_[b].slot; });
  std::vector<std::uint32_t> position(order.size());
  std::vector<LeafRecord> sorted;
  sorted.reserve(order.size());
  for (std::uint32_t i = 0; i < order.size(); ++i)
  {
    position[order[i]] = i;
    sorted.push_back(leaves_[order[i]]);
  }
  leaves_ = std::move(sorted);
  for (auto& entry : nodes_)
    for (std::uint32_t& l : entry.second.leaves) l = position[l];
}

}  // namespace line_map_merging
