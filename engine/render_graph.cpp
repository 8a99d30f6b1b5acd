#include "engine/render_graph.h"

#include <algorithm>
#include <iterator>
#include <sstream>
#include <utility>

#include "engine/device.h"
#include "engine/pass_counters.h"
#include "engine/timing.h"

namespace canopy::rg {

namespace {

constexpr VkAccessFlags2 kWriteBits =
    VK_ACCESS_2_SHADER_WRITE_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT | VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT |
    VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT | VK_ACCESS_2_TRANSFER_WRITE_BIT | VK_ACCESS_2_HOST_WRITE_BIT |
    VK_ACCESS_2_MEMORY_WRITE_BIT;

// Per-resource synchronization bookkeeping while walking the schedule.
struct Track {
  VkPipelineStageFlags2 writeStage = 0;    // stages of the last write (or layout transition)
  VkAccessFlags2 writeAccess = 0;          // its write accesses, to be made available
  VkPipelineStageFlags2 readStages = 0;    // reads since that write (for write-after-read)
  VkPipelineStageFlags2 visibleStages = 0; // (stage, access) already synchronized with the write
  VkAccessFlags2 visibleAccess = 0;
  // An imported resource that enters in a read state: the stages its earlier writes and layout
  // transition were made visible to (the barrier that put it there named only those). A read at
  // another stage chains a barrier from them; no write of this graph's is pending.
  VkPipelineStageFlags2 chainStage = 0;
  VkImageLayout layout = VK_IMAGE_LAYOUT_UNDEFINED;
  bool touched = false;
};

Track trackFrom(const State& s) {
  Track t;
  t.layout = s.layout;
  if (isWriteAccess(s.access)) {
    t.writeStage = s.stage;
    t.writeAccess = s.access & kWriteBits;
  } else {
    t.readStages = s.stage;
    t.chainStage = s.stage;
    t.visibleStages = s.stage;
    t.visibleAccess = s.access;
  }
  return t;
}

void addBarrier(std::vector<Barrier>& list, const Barrier& b) {
  for (Barrier& e : list) {
    if (e.resource == b.resource && e.oldLayout == b.oldLayout && e.newLayout == b.newLayout &&
        e.srcStage == b.srcStage && e.srcAccess == b.srcAccess) {
      e.dstStage |= b.dstStage;
      e.dstAccess |= b.dstAccess;
      return;
    }
  }
  list.push_back(b);
}

std::string flagsHex(uint64_t v) {
  std::ostringstream o;
  o << "0x" << std::hex << v;
  return o.str();
}

// Short names of the stage and access bits the graph uses, for describe().
std::string bitNames(uint64_t v, const std::pair<uint64_t, const char*>* table, size_t n) {
  if (!v) return "none";
  std::string s;
  for (size_t i = 0; i < n; ++i)
    if ((v & table[i].first) == table[i].first) {
      if (!s.empty()) s += '|';  // appends: GCC 12's -Wrestrict misfires on "" + std::string(...)
      s += table[i].second;
      v &= ~table[i].first;
    }
  if (v) {
    if (!s.empty()) s += '|';
    s += flagsHex(v);
  }
  return s;
}
std::string stageNames(VkPipelineStageFlags2 v) {
  static const std::pair<uint64_t, const char*> t[] = {
      {VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, "compute"}, {VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, "fragment"},
      {VK_PIPELINE_STAGE_2_VERTEX_SHADER_BIT, "vertex"}, {VK_PIPELINE_STAGE_2_VERTEX_ATTRIBUTE_INPUT_BIT, "vertex-input"},
      {VK_PIPELINE_STAGE_2_INDEX_INPUT_BIT, "index-input"}, {VK_PIPELINE_STAGE_2_DRAW_INDIRECT_BIT, "indirect"},
      {VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, "color-output"},
      {VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT, "depth-tests"},
      {VK_PIPELINE_STAGE_2_TRANSFER_BIT, "transfer"}, {VK_PIPELINE_STAGE_2_HOST_BIT, "host"}};
  return bitNames(v, t, std::size(t));
}
std::string accessNames(VkAccessFlags2 v) {
  static const std::pair<uint64_t, const char*> t[] = {
      {VK_ACCESS_2_SHADER_STORAGE_READ_BIT, "storage-read"}, {VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, "storage-write"},
      {VK_ACCESS_2_SHADER_SAMPLED_READ_BIT, "sampled-read"}, {VK_ACCESS_2_UNIFORM_READ_BIT, "uniform-read"},
      {VK_ACCESS_2_COLOR_ATTACHMENT_READ_BIT, "color-read"}, {VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT, "color-write"},
      {VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT, "depth-read"},
      {VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT, "depth-write"}, {VK_ACCESS_2_TRANSFER_READ_BIT, "transfer-read"},
      {VK_ACCESS_2_TRANSFER_WRITE_BIT, "transfer-write"}, {VK_ACCESS_2_HOST_READ_BIT, "host-read"},
      {VK_ACCESS_2_HOST_WRITE_BIT, "host-write"}, {VK_ACCESS_2_VERTEX_ATTRIBUTE_READ_BIT, "vertex-read"},
      {VK_ACCESS_2_INDEX_READ_BIT, "index-read"}, {VK_ACCESS_2_INDIRECT_COMMAND_READ_BIT, "indirect-read"}};
  return bitNames(v, t, std::size(t));
}
const char* layoutName(VkImageLayout l) {
  switch (l) {
    case VK_IMAGE_LAYOUT_UNDEFINED: return "undefined";
    case VK_IMAGE_LAYOUT_GENERAL: return "general";
    case VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL: return "color-attachment";
    case VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL: return "depth-attachment";
    case VK_IMAGE_LAYOUT_DEPTH_STENCIL_READ_ONLY_OPTIMAL: return "depth-read-only";
    case VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL: return "shader-read-only";
    case VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL: return "transfer-src";
    case VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL: return "transfer-dst";
    case VK_IMAGE_LAYOUT_PRESENT_SRC_KHR: return "present";
    default: return "other";
  }
}

}  // namespace

bool isWriteAccess(VkAccessFlags2 access) { return (access & kWriteBits) != 0; }

State stateOf(Use use) {
  const VkImageLayout GEN = VK_IMAGE_LAYOUT_GENERAL;
  switch (use) {
    case Use::ComputeStorageRead: return {VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_READ_BIT, GEN};
    case Use::ComputeStorageWrite: return {VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, GEN};
    case Use::ComputeStorageReadWrite:
      return {VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
              VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, GEN};
    case Use::ComputeSampled:
      return {VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_SAMPLED_READ_BIT,
              VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
    case Use::ComputeUniform: return {VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_UNIFORM_READ_BIT, GEN};
    case Use::FragmentSampled:
      return {VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, VK_ACCESS_2_SHADER_SAMPLED_READ_BIT,
              VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
    case Use::FragmentStorageRead: return {VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_READ_BIT, GEN};
    case Use::FragmentUniform: return {VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, VK_ACCESS_2_UNIFORM_READ_BIT, GEN};
    case Use::VertexStorageRead: return {VK_PIPELINE_STAGE_2_VERTEX_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_READ_BIT, GEN};
    case Use::VertexBuffer: return {VK_PIPELINE_STAGE_2_VERTEX_ATTRIBUTE_INPUT_BIT, VK_ACCESS_2_VERTEX_ATTRIBUTE_READ_BIT, GEN};
    case Use::IndexBuffer: return {VK_PIPELINE_STAGE_2_INDEX_INPUT_BIT, VK_ACCESS_2_INDEX_READ_BIT, GEN};
    case Use::IndirectBuffer: return {VK_PIPELINE_STAGE_2_DRAW_INDIRECT_BIT, VK_ACCESS_2_INDIRECT_COMMAND_READ_BIT, GEN};
    case Use::ColorAttachmentWrite:
      return {VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT,
              VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
    case Use::ColorAttachmentReadWrite:
      return {VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
              VK_ACCESS_2_COLOR_ATTACHMENT_READ_BIT | VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT,
              VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
    case Use::DepthAttachmentWrite:
      return {VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT,
              VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT | VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT,
              VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL};
    case Use::DepthAttachmentRead:
      return {VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT,
              VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT, VK_IMAGE_LAYOUT_DEPTH_STENCIL_READ_ONLY_OPTIMAL};
    case Use::TransferSrc: return {VK_PIPELINE_STAGE_2_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_READ_BIT, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL};
    case Use::TransferDst: return {VK_PIPELINE_STAGE_2_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL};
    case Use::HostRead: return {VK_PIPELINE_STAGE_2_HOST_BIT, VK_ACCESS_2_HOST_READ_BIT, GEN};
  }
  return {};
}

std::string toString(const Barrier& b) {
  std::ostringstream o;
  o << "r" << b.resource << " src(" << flagsHex(b.srcStage) << "," << flagsHex(b.srcAccess) << ") dst("
    << flagsHex(b.dstStage) << "," << flagsHex(b.dstAccess) << ") layout " << b.oldLayout << "->" << b.newLayout;
  return o.str();
}

// ---- PassContext ----------------------------------------------------------------------------
VkBuffer PassContext::buffer(ResourceId id) const { return graph->buffer(id); }
const Image& PassContext::image(ResourceId id) const { return graph->image(id); }

// ---- declaration ------------------------------------------------------------------------------
ResourceId RenderGraph::createBuffer(std::string name, const BufferInfo& info) {
  Resource r;
  r.name = std::move(name);
  r.bufferInfo = info;
  resources_.push_back(std::move(r));
  compiled_ = false;
  return ResourceId(resources_.size() - 1);
}

ResourceId RenderGraph::createImage(std::string name, const ImageDesc& desc) {
  Resource r;
  r.name = std::move(name);
  r.isImage = true;
  r.imageDesc = desc;
  resources_.push_back(std::move(r));
  compiled_ = false;
  return ResourceId(resources_.size() - 1);
}

ResourceId RenderGraph::importBuffer(std::string name, VkDeviceSize size, State initial, State final) {
  ResourceId id = createBuffer(std::move(name), BufferInfo{size});
  resources_[id].imported = true;
  resources_[id].initial = initial;
  resources_[id].final = final;
  return id;
}

ResourceId RenderGraph::importImage(std::string name, const ImageDesc& desc, State initial, State final) {
  ResourceId id = createImage(std::move(name), desc);
  resources_[id].imported = true;
  resources_[id].initial = initial;
  resources_[id].final = final;
  if (final.layout == VK_IMAGE_LAYOUT_UNDEFINED && error_.empty())
    error_ = "imported image '" + resources_[id].name + "' needs a final layout (VK_IMAGE_LAYOUT_UNDEFINED given)";
  return id;
}

RenderGraph::PassBuilder RenderGraph::addPass(std::string name, PassFn fn) {
  Pass p;
  p.name = std::move(name);
  p.fn = std::move(fn);
  passes_.push_back(std::move(p));
  compiled_ = false;
  return PassBuilder(this, uint32_t(passes_.size() - 1));
}

void RenderGraph::markOutput(ResourceId id) {
  if (id < resources_.size()) resources_[id].output = true;
  compiled_ = false;
}

State RenderGraph::combinedUse(ResourceId id) const {
  State u;
  u.layout = id < resources_.size() ? resources_[id].initial.layout : VK_IMAGE_LAYOUT_UNDEFINED;
  for (const Step& s : steps_)
    for (uint32_t pi : s.passes)
      for (const AccessDecl& a : passes_[pi].accesses)
        if (a.id == id) {
          u.stage |= a.state.stage;
          u.access |= a.state.access;
          u.layout = a.state.layout;
        }
  return u;
}

ResourceId RenderGraph::findResource(const std::string& name) const {
  for (size_t i = 0; i < resources_.size(); ++i)
    if (resources_[i].name == name) return ResourceId(i);
  return kInvalidResource;
}

void RenderGraph::addAccess(uint32_t pass, ResourceId id, State s) {
  Pass& p = passes_[pass];
  if (id >= resources_.size()) {
    if (error_.empty()) error_ = "pass '" + p.name + "' uses an unknown resource id " + std::to_string(id);
    return;
  }
  // Several declarations of one resource in one pass merge into one access.
  for (AccessDecl& a : p.accesses) {
    if (a.id != id) continue;
    if (resources_[id].isImage && a.state.layout != s.layout && error_.empty())
      error_ = "pass '" + p.name + "' uses image '" + resources_[id].name + "' in two layouts";
    a.state.stage |= s.stage;
    a.state.access |= s.access;
    return;
  }
  p.accesses.push_back({id, s});
  compiled_ = false;
}

RenderGraph::PassBuilder& RenderGraph::PassBuilder::read(ResourceId id, Use use) {
  State s = stateOf(use);
  if (isWriteAccess(s.access) && graph_->error_.empty())
    graph_->error_ = "pass '" + graph_->passes_[pass_].name + "' declares a writing use as read()";
  graph_->addAccess(pass_, id, s);
  return *this;
}
RenderGraph::PassBuilder& RenderGraph::PassBuilder::write(ResourceId id, Use use) {
  State s = stateOf(use);
  if (!isWriteAccess(s.access) && graph_->error_.empty())
    graph_->error_ = "pass '" + graph_->passes_[pass_].name + "' declares a read-only use as write()";
  graph_->addAccess(pass_, id, s);
  return *this;
}
RenderGraph::PassBuilder& RenderGraph::PassBuilder::access(ResourceId id, State state) {
  graph_->addAccess(pass_, id, state);
  return *this;
}
RenderGraph::PassBuilder& RenderGraph::PassBuilder::sideEffect() {
  graph_->passes_[pass_].sideEffect = true;
  return *this;
}

RenderGraph::PassBuilder& RenderGraph::PassBuilder::when(std::function<bool()> enabled) {
  graph_->passes_[pass_].enabled = std::move(enabled);
  return *this;
}

// ---- compile ----------------------------------------------------------------------------------
Status RenderGraph::compile() {
  if (!error_.empty()) return Status::error(error_);
  steps_.clear();
  final_.clear();
  const size_t P = passes_.size(), R = resources_.size();

  // 1. Culling, backwards: a pass is needed when it has a side effect, writes an imported or
  //    output resource, or writes something a needed later pass reads. Writes do not end the
  //    need for earlier writers (a write may be partial), so culling is conservative.
  std::vector<bool> wanted(R, false);
  for (size_t i = P; i-- > 0;) {
    Pass& p = passes_[i];
    bool needed = p.sideEffect;
    for (const AccessDecl& a : p.accesses) {
      const Resource& r = resources_[a.id];
      if (isWriteAccess(a.state.access) && (r.imported || r.output || wanted[a.id])) needed = true;
    }
    p.culled = !needed;
    if (needed)
      for (const AccessDecl& a : p.accesses)
        if (a.state.access & ~kWriteBits) wanted[a.id] = true;
  }

  // 2. Dependencies (read-after-write, write-after-read, write-after-write; a layout change is a
  //    write) in declaration order, then the level of each pass in the dependency DAG.
  struct DepTrack {
    int lastWriter = -1;
    std::vector<int> readers;
    VkImageLayout layout = VK_IMAGE_LAYOUT_UNDEFINED;
    bool written = false;
  };
  std::vector<DepTrack> dt(R);
  for (size_t r = 0; r < R; ++r)
    if (resources_[r].imported) {
      dt[r].layout = resources_[r].initial.layout;
      dt[r].written = true;
    }
  std::vector<int> level(P, 0);
  for (size_t i = 0; i < P; ++i) {
    Pass& p = passes_[i];
    if (p.culled) continue;
    int lv = 0;
    auto dependOn = [&](int j) { if (j >= 0) lv = std::max(lv, level[j] + 1); };
    for (const AccessDecl& a : p.accesses) {
      DepTrack& t = dt[a.id];
      const Resource& r = resources_[a.id];
      const bool reads = (a.state.access & ~kWriteBits) != 0;
      const bool layoutChange = r.isImage && a.state.layout != t.layout;
      const bool writes = isWriteAccess(a.state.access) || layoutChange;
      if (reads && !t.written && !r.imported)
        return Status::error("pass '" + p.name + "' reads '" + r.name + "' before any pass writes it");
      dependOn(t.lastWriter);
      if (writes) {
        for (int j : t.readers) dependOn(j);
        t.readers.clear();
      } else {
        t.readers.push_back(int(i));
      }
    }
    level[i] = lv;
    for (const AccessDecl& a : p.accesses) {
      DepTrack& t = dt[a.id];
      const Resource& r = resources_[a.id];
      const bool layoutChange = r.isImage && a.state.layout != t.layout;
      if (isWriteAccess(a.state.access) || layoutChange) {
        t.lastWriter = int(i);
        t.written = true;
      }
      t.layout = a.state.layout;
    }
  }
  int maxLevel = -1;
  for (size_t i = 0; i < P; ++i)
    if (!passes_[i].culled) maxLevel = std::max(maxLevel, level[i]);
  std::vector<Step> steps(size_t(maxLevel + 1));
  for (size_t i = 0; i < P; ++i)
    if (!passes_[i].culled) steps[size_t(level[i])].passes.push_back(uint32_t(i));

  for (size_t i = 0; i < P; ++i) {
    const Pass& p = passes_[i];
    if (!p.enabled || p.culled) continue;
    for (const AccessDecl& a : p.accesses)
      if (!resources_[a.id].imported)
        return Status::error("pass '" + p.name + "' runs only in some frames (when) but accesses the transient '" +
                             resources_[a.id].name + "'");
  }
  // 3. Barriers, every pass enabled; record() plans other combinations of conditional passes.
  planBarriers(std::vector<bool>(P, false), steps, final_);
  steps_ = std::move(steps);
  full_ = Plan{steps_, final_, std::vector<bool>(P, false)};
  conditionalPlans_.clear();
  compiled_ = true;
  return Status();
}

void RenderGraph::planBarriers(const std::vector<bool>& skip, std::vector<Step>& steps, std::vector<Barrier>& fin) const {
  const size_t R = resources_.size();
  fin.clear();
  // 3. Barriers. Transients start each frame from the state the previous frame left them in
  //    (contents discarded: layout UNDEFINED), so frame N+1 never races frame N. That needs the
  //    end-of-frame state first, hence two sweeps.
  auto sweep = [&](std::vector<Track> tracks, std::vector<Step>* out, std::vector<Barrier>* finOut) {
    for (size_t s = 0; s < steps.size(); ++s) {
      std::vector<Barrier> batch;
      for (uint32_t pi : steps[s].passes) {
        if (skip[pi]) continue;
        for (const AccessDecl& a : passes_[pi].accesses) {
          Track& t = tracks[a.id];
          const Resource& r = resources_[a.id];
          const bool layoutChange = r.isImage && a.state.layout != t.layout;
          const bool writes = isWriteAccess(a.state.access) || layoutChange;
          const VkImageLayout newLayout = r.isImage ? a.state.layout : VK_IMAGE_LAYOUT_UNDEFINED;
          const VkImageLayout oldLayout = r.isImage ? t.layout : VK_IMAGE_LAYOUT_UNDEFINED;
          t.touched = true;
          if (!writes) {
            const VkPipelineStageFlags2 missStage = a.state.stage & ~t.visibleStages;
            const VkAccessFlags2 missAccess = a.state.access & ~t.visibleAccess;
            if (t.writeStage && (missStage || missAccess))
              addBarrier(batch, {a.id, t.writeStage, t.writeAccess, a.state.stage, a.state.access, oldLayout, newLayout});
            else if (t.chainStage && (missStage || missAccess))
              addBarrier(batch, {a.id, t.chainStage, 0, a.state.stage, a.state.access, oldLayout, newLayout});
            t.visibleStages |= a.state.stage;
            t.visibleAccess |= a.state.access;
            t.readStages |= a.state.stage;
          } else {
            const VkPipelineStageFlags2 src = t.writeStage | t.readStages;
            if (src || layoutChange)
              addBarrier(batch, {a.id, src, t.writeAccess, a.state.stage, a.state.access, oldLayout, newLayout});
            t.writeStage = a.state.stage;
            t.writeAccess = a.state.access & kWriteBits;
            t.readStages = 0;
            t.chainStage = 0;
            // A pure layout transition is visible to the barrier's destination scope already.
            t.visibleStages = t.writeAccess ? 0 : a.state.stage;
            t.visibleAccess = t.writeAccess ? 0 : a.state.access;
            t.layout = a.state.layout;
          }
        }
      }
      if (out) {
        (*out)[s].barriers = std::move(batch);
      }
    }
    for (size_t r = 0; r < R; ++r) {
      const Resource& res = resources_[r];
      Track& t = tracks[r];
      if (!res.imported) continue;
      const VkImageLayout finalLayout = res.isImage ? res.final.layout : VK_IMAGE_LAYOUT_UNDEFINED;
      const bool layoutChange = res.isImage && finalLayout != t.layout;
      const bool pending = t.writeAccess != 0 || (t.readStages && isWriteAccess(res.final.access));
      const bool callerSynchronizes = res.isImage && res.final.stage == 0 && !layoutChange;
      // Reads at stages the final state does not name are waited for too: the next frame's first
      // write starts from the final state's stages alone.
      const bool otherReaders = t.touched && res.final.stage && (t.readStages & ~res.final.stage) != 0;
      if (!callerSynchronizes &&
          (layoutChange || (t.touched && pending) || (t.touched && t.writeStage && res.final.stage) || otherReaders)) {
        if (finOut)
          finOut->push_back({ResourceId(r), t.writeStage | t.readStages, t.writeAccess, res.final.stage, res.final.access,
                          res.isImage ? t.layout : VK_IMAGE_LAYOUT_UNDEFINED, finalLayout});
      }
    }
    return tracks;
  };
  std::vector<Track> init(R);
  for (size_t r = 0; r < R; ++r)
    if (resources_[r].imported) init[r] = trackFrom(resources_[r].initial);
  std::vector<Track> end = sweep(init, nullptr, nullptr);
  for (size_t r = 0; r < R; ++r) {
    if (resources_[r].imported || !end[r].touched) continue;
    Track t;
    t.readStages = end[r].writeStage | end[r].readStages;  // wait for last frame's uses
    t.writeStage = 0;
    t.writeAccess = 0;
    // Contents are not carried across frames, so prior writes need no visibility: an execution
    // dependency (write-after-read/write) is what protects them.
    t.layout = VK_IMAGE_LAYOUT_UNDEFINED;
    init[r] = t;
  }
  sweep(init, &steps, &fin);
}

std::string RenderGraph::describe() const {
  std::ostringstream o;
  auto bar = [&](const Barrier& b) {
    o << "    barrier " << resources_[b.resource].name << ": " << stageNames(b.srcStage) << "/"
      << accessNames(b.srcAccess) << " -> " << stageNames(b.dstStage) << "/" << accessNames(b.dstAccess);
    if (resources_[b.resource].isImage) o << ", layout " << layoutName(b.oldLayout) << " -> " << layoutName(b.newLayout);
    o << "\n";
  };
  for (size_t s = 0; s < steps_.size(); ++s) {
    o << "step " << s << ":\n";
    for (const Barrier& b : steps_[s].barriers) bar(b);
    for (uint32_t p : steps_[s].passes) o << "    pass " << passes_[p].name << "\n";
  }
  o << "final:\n";
  for (const Barrier& b : final_) bar(b);
  for (size_t p = 0; p < passes_.size(); ++p)
    if (passes_[p].culled) o << "culled: " << passes_[p].name << "\n";
  return o.str();
}

// ---- resources --------------------------------------------------------------------------------
namespace {
VkBufferUsageFlags bufferUsageFrom(VkAccessFlags2 a) {
  VkBufferUsageFlags u = 0;
  if (a & (VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT | VK_ACCESS_2_SHADER_READ_BIT |
           VK_ACCESS_2_SHADER_WRITE_BIT))
    u |= VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
  if (a & VK_ACCESS_2_UNIFORM_READ_BIT) u |= VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT;
  if (a & VK_ACCESS_2_TRANSFER_READ_BIT) u |= VK_BUFFER_USAGE_TRANSFER_SRC_BIT;
  if (a & VK_ACCESS_2_TRANSFER_WRITE_BIT) u |= VK_BUFFER_USAGE_TRANSFER_DST_BIT;
  if (a & VK_ACCESS_2_VERTEX_ATTRIBUTE_READ_BIT) u |= VK_BUFFER_USAGE_VERTEX_BUFFER_BIT;
  if (a & VK_ACCESS_2_INDEX_READ_BIT) u |= VK_BUFFER_USAGE_INDEX_BUFFER_BIT;
  if (a & VK_ACCESS_2_INDIRECT_COMMAND_READ_BIT) u |= VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT;
  return u;
}
VkImageUsageFlags imageUsageFrom(VkAccessFlags2 a) {
  VkImageUsageFlags u = 0;
  if (a & (VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT)) u |= VK_IMAGE_USAGE_STORAGE_BIT;
  if (a & VK_ACCESS_2_SHADER_SAMPLED_READ_BIT) u |= VK_IMAGE_USAGE_SAMPLED_BIT;
  if (a & (VK_ACCESS_2_COLOR_ATTACHMENT_READ_BIT | VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT))
    u |= VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT;
  if (a & (VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT | VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT))
    u |= VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT;
  if (a & VK_ACCESS_2_TRANSFER_READ_BIT) u |= VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
  if (a & VK_ACCESS_2_TRANSFER_WRITE_BIT) u |= VK_IMAGE_USAGE_TRANSFER_DST_BIT;
  return u;
}
}  // namespace

Status RenderGraph::realize(Device& device) {
  if (!compiled_) CANOPY_TRY(compile());
  release(device);
  device_ = &device;
  std::vector<VkAccessFlags2> uses(resources_.size(), 0);
  for (const Pass& p : passes_)
    if (!p.culled)
      for (const AccessDecl& a : p.accesses) uses[a.id] |= a.state.access;
  for (size_t i = 0; i < resources_.size(); ++i) {
    Resource& r = resources_[i];
    if (r.imported || uses[i] == 0) continue;
    if (r.isImage) {
      ImageDesc d = r.imageDesc;
      d.usage |= imageUsageFrom(uses[i]);
      CANOPY_TRY(::canopy::createImage(device, d, &r.image, r.name.c_str()).context("render graph transient"));
    } else {
      CANOPY_TRY(::canopy::createBuffer(device, r.bufferInfo.size, bufferUsageFrom(uses[i]) | r.bufferInfo.extraUsage,
                              r.bufferInfo.memory, &r.ownedBuffer, r.name.c_str())
                     .context("render graph transient"));
      r.buffer = r.ownedBuffer.buffer;
    }
    r.owned = true;
  }
  return Status();
}

void RenderGraph::release(Device& device) {
  for (Resource& r : resources_) {
    if (!r.owned) continue;
    if (r.isImage) destroyImage(device, r.image);
    else destroyBuffer(device, r.ownedBuffer);
    r.buffer = VK_NULL_HANDLE;
    r.owned = false;
  }
}

Status RenderGraph::bindBuffer(ResourceId id, VkBuffer buffer) {
  if (id >= resources_.size() || !resources_[id].imported || resources_[id].isImage)
    return Status::error("bindBuffer: resource " + std::to_string(id) + " is not an imported buffer");
  resources_[id].buffer = buffer;
  return Status();
}

Status RenderGraph::bindImage(ResourceId id, const Image& image) {
  if (id >= resources_.size() || !resources_[id].imported || !resources_[id].isImage)
    return Status::error("bindImage: resource " + std::to_string(id) + " is not an imported image");
  resources_[id].image = image;
  return Status();
}

// ---- record -----------------------------------------------------------------------------------
void RenderGraph::passBytes(uint32_t pass, uint64_t* bytesRead, uint64_t* bytesWritten) const {
  *bytesRead = *bytesWritten = 0;
  for (const AccessDecl& a : passes_.at(pass).accesses) {
    const Resource& r = resources_[a.id];
    const uint64_t bytes = r.isImage ? uint64_t(r.imageDesc.width) * r.imageDesc.height * std::max<uint32_t>(r.imageDesc.layers, 1) *
                                           texelBytes(r.imageDesc.format)
                                     : uint64_t(r.bufferInfo.size);
    const bool writes = isWriteAccess(a.state.access);
    const bool reads = (a.state.access & ~(VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT | VK_ACCESS_2_SHADER_WRITE_BIT | VK_ACCESS_2_TRANSFER_WRITE_BIT |
                                           VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT | VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT |
                                           VK_ACCESS_2_HOST_WRITE_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT)) != 0;
    if (reads) *bytesRead += bytes;
    if (writes) *bytesWritten += bytes;
  }
}

Status RenderGraph::record(VkCommandBuffer cmd, GpuTimer* timer, PassCounters* counters) {
  if (!compiled_) return Status::error("render graph: record() before compile()");
  if (!device_) return Status::error("render graph: record() before realize()");
  for (const Pass& p : passes_) {
    if (p.culled) continue;
    for (const AccessDecl& a : p.accesses) {
      const Resource& r = resources_[a.id];
      if (r.isImage ? r.image.image == VK_NULL_HANDLE : r.buffer == VK_NULL_HANDLE)
        return Status::error("render graph: resource '" + r.name + "' used by pass '" + p.name +
                             "' has no Vulkan object (imported but not bound?)");
    }
  }
  std::vector<VkBufferMemoryBarrier2> bb;
  std::vector<VkImageMemoryBarrier2> ib;
  auto emit = [&](const std::vector<Barrier>& list) {
    if (list.empty()) return;
    bb.clear();
    ib.clear();
    for (const Barrier& b : list) {
      const Resource& r = resources_[b.resource];
      if (r.isImage) {
        VkImageMemoryBarrier2 x{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER_2};
        x.srcStageMask = b.srcStage;
        x.srcAccessMask = b.srcAccess;
        x.dstStageMask = b.dstStage;
        x.dstAccessMask = b.dstAccess;
        x.oldLayout = b.oldLayout;
        x.newLayout = b.newLayout;
        x.srcQueueFamilyIndex = x.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
        x.image = r.image.image;
        x.subresourceRange = {aspectOf(r.image.format ? r.image.format : r.imageDesc.format), 0, VK_REMAINING_MIP_LEVELS,
                              0, VK_REMAINING_ARRAY_LAYERS};
        ib.push_back(x);
      } else {
        VkBufferMemoryBarrier2 x{VK_STRUCTURE_TYPE_BUFFER_MEMORY_BARRIER_2};
        x.srcStageMask = b.srcStage;
        x.srcAccessMask = b.srcAccess;
        x.dstStageMask = b.dstStage;
        x.dstAccessMask = b.dstAccess;
        x.srcQueueFamilyIndex = x.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
        x.buffer = r.buffer;
        x.offset = 0;
        x.size = VK_WHOLE_SIZE;
        bb.push_back(x);
      }
    }
    VkDependencyInfo dep{VK_STRUCTURE_TYPE_DEPENDENCY_INFO};
    dep.bufferMemoryBarrierCount = uint32_t(bb.size());
    dep.pBufferMemoryBarriers = bb.data();
    dep.imageMemoryBarrierCount = uint32_t(ib.size());
    dep.pImageMemoryBarriers = ib.data();
    device_->cmdPipelineBarrier2(cmd, &dep);
  };
  const Plan& plan = currentPlan();
  PassContext ctx{cmd, device_, this};
  for (const Step& s : plan.steps) {
    emit(s.barriers);
    for (uint32_t pi : s.passes) {
      if (plan.skipped[pi]) continue;
      Pass& p = passes_[pi];
      if (timer) timer->begin(cmd, p.name);
      if (counters) {
        uint64_t read = 0, written = 0;
        passBytes(pi, &read, &written);
        counters->begin(cmd, p.name, read, written);
      }
      Status st = p.fn ? p.fn(ctx) : Status();
      if (counters) counters->end(cmd);
      if (timer) timer->end(cmd);
      if (!st.ok()) return st.context("pass '" + p.name + "'");
    }
  }
  emit(plan.final);
  return Status();
}

const RenderGraph::Plan& RenderGraph::currentPlan() {
  std::vector<bool> skip(passes_.size(), false);
  bool any = false;
  for (size_t i = 0; i < passes_.size(); ++i)
    if (passes_[i].enabled && !passes_[i].culled && !passes_[i].enabled()) skip[i] = any = true;
  if (!any) return full_;
  for (const Plan& p : conditionalPlans_)
    if (p.skipped == skip) return p;
  Plan p{steps_, {}, skip};
  planBarriers(skip, p.steps, p.final);
  conditionalPlans_.push_back(std::move(p));
  return conditionalPlans_.back();
}

}  // namespace canopy::rg
