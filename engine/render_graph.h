#pragma once
// Render graph (Granite/vuk style): passes declare what they read and write; the graph derives
// the execution order, culls passes whose results nobody uses, creates transient resources and
// emits every synchronization2 barrier and layout transition. Host resources are *imported* with
// the state they arrive in and the state they must be left in — this is how a host engine embeds
// Canopy. compile() is pure CPU (the barrier plan is inspectable and unit-tested); realize()
// creates the transients once; record() re-records the compiled plan cheaply every frame.
#include <functional>
#include <string>
#include <vector>
#include <vulkan/vulkan.h>

#include "engine/memory.h"
#include "engine/status.h"

namespace canopy {
struct Device;
class GpuTimer;
class PassCounters;
}

namespace canopy::rg {

using ResourceId = uint32_t;
inline constexpr ResourceId kInvalidResource = ~0u;

// A resource's synchronization state: the stages/accesses that last touched it and its layout.
// (The public ResourceState of <canopy/canopy.h>: the states a host hands recordCanopy. The layout
// is ignored for buffers.)
using State = ::canopy::ResourceState;

// The common ways a pass touches a resource; each maps to one State (stateOf).
enum class Use {
  ComputeStorageRead,
  ComputeStorageWrite,
  ComputeStorageReadWrite,
  ComputeSampled,
  ComputeUniform,
  FragmentSampled,
  FragmentStorageRead,
  FragmentUniform,
  VertexStorageRead,
  VertexBuffer,
  IndexBuffer,
  IndirectBuffer,
  ColorAttachmentWrite,
  ColorAttachmentReadWrite,  // blending
  DepthAttachmentWrite,
  DepthAttachmentRead,
  TransferSrc,
  TransferDst,
  HostRead,
};
State stateOf(Use use);
// True when `access` contains any write access bit.
bool isWriteAccess(VkAccessFlags2 access);

struct Barrier {
  ResourceId resource = kInvalidResource;
  VkPipelineStageFlags2 srcStage = 0;
  VkAccessFlags2 srcAccess = 0;
  VkPipelineStageFlags2 dstStage = 0;
  VkAccessFlags2 dstAccess = 0;
  VkImageLayout oldLayout = VK_IMAGE_LAYOUT_UNDEFINED;  // both UNDEFINED for buffers
  VkImageLayout newLayout = VK_IMAGE_LAYOUT_UNDEFINED;
  bool operator==(const Barrier&) const = default;
};
std::string toString(const Barrier& b);

// One dependency level of the schedule: its barriers are issued as one batch, then its passes
// (mutually independent) run in declaration order.
struct Step {
  std::vector<Barrier> barriers;
  std::vector<uint32_t> passes;
};

struct BufferInfo {
  VkDeviceSize size = 0;
  VkBufferUsageFlags extraUsage = 0;  // added to the usage derived from the declared uses
  MemoryUsage memory = MemoryUsage::DeviceLocal;
};

class RenderGraph;

struct PassContext {
  VkCommandBuffer cmd = VK_NULL_HANDLE;
  Device* device = nullptr;
  const RenderGraph* graph = nullptr;
  VkBuffer buffer(ResourceId id) const;
  const Image& image(ResourceId id) const;
};
using PassFn = std::function<Status(PassContext&)>;

class RenderGraph {
 public:
  class PassBuilder {
   public:
    PassBuilder& read(ResourceId id, Use use);
    PassBuilder& write(ResourceId id, Use use);
    // Explicit form: whether it writes is decided by the access bits (and a layout change).
    PassBuilder& access(ResourceId id, State state);
    // Never culled (e.g. a pass whose effect is outside the graph).
    PassBuilder& sideEffect();
    // A pass that runs only in frames where `enabled` returns true (asked once per record()): in
    // the others neither it nor its barriers are recorded, so a pass that works now and then (a
    // re-slice) costs nothing in the frames between. It may access imported resources only (a
    // transient's state would then differ from frame to frame); compile() refuses others.
    PassBuilder& when(std::function<bool()> enabled);

   private:
    friend class RenderGraph;
    PassBuilder(RenderGraph* g, uint32_t p) : graph_(g), pass_(p) {}
    RenderGraph* graph_;
    uint32_t pass_;
  };

  // Transient resources: created by realize(), contents undefined at the start of every frame.
  ResourceId createBuffer(std::string name, const BufferInfo& info);
  ResourceId createImage(std::string name, const ImageDesc& desc);
  // Imported resources: owned by the caller, bound with bindBuffer/bindImage before record().
  // `initial` is how the caller last used it (pending writes are made visible to the first pass);
  // `final` is how the caller will use it next (the graph leaves it in that state). An image's
  // `final` with no stage and the layout the last pass leaves means the caller synchronizes after
  // the graph itself (a host graph around Canopy's pass group): no final barrier is recorded.
  ResourceId importBuffer(std::string name, VkDeviceSize size, State initial, State final);
  ResourceId importImage(std::string name, const ImageDesc& desc, State initial, State final);

  PassBuilder addPass(std::string name, PassFn fn);
  // Keeps the producers of a transient alive although no pass reads it.
  void markOutput(ResourceId id);

  // Culls, schedules and plans barriers. Pure CPU; an error names the pass and resource.
  Status compile();
  const std::vector<Step>& steps() const { return steps_; }
  const std::vector<Barrier>& finalBarriers() const { return final_; }
  bool isCulled(uint32_t pass) const { return passes_.at(pass).culled; }
  uint32_t passCount() const { return uint32_t(passes_.size()); }
  const std::string& passName(uint32_t pass) const { return passes_.at(pass).name; }
  const std::string& resourceName(ResourceId id) const { return resources_.at(id).name; }
  ResourceId findResource(const std::string& name) const;
  // After compile(): every stage and access the passes make to `id`, with the layout the last of
  // them leaves it in (how a host's graph declares this whole graph as one pass).
  State combinedUse(ResourceId id) const;
  // The Vulkan objects behind a resource (after realize()/bind*()).
  VkBuffer buffer(ResourceId id) const { return resources_.at(id).buffer; }
  const Image& image(ResourceId id) const { return resources_.at(id).image; }
  // The schedule as text, one step a line: barriers then passes (for logs and test failures).
  std::string describe() const;

  // Creates the transient resources (usage flags derived from the declared uses).
  Status realize(Device& device);
  void release(Device& device);
  Status bindBuffer(ResourceId id, VkBuffer buffer);
  Status bindImage(ResourceId id, const Image& image);

  // Records barriers and passes into `cmd`; with a timer each pass is wrapped in timestamps, with
  // counters in pipeline statistics queries (with the bytes of its declared accesses).
  Status record(VkCommandBuffer cmd, GpuTimer* timer = nullptr, PassCounters* counters = nullptr);
  // The bytes of the resources pass `pass` declares it reads and writes, whole (buffers: their
  // size; images: width x height x layers x texel size): an estimate of its traffic.
  void passBytes(uint32_t pass, uint64_t* bytesRead, uint64_t* bytesWritten) const;

  // The schedule record() would use now: the passes whose `when` is false left out, with the
  // barriers planned without their accesses (planned once per combination, then cached).
  struct Plan {
    std::vector<Step> steps;
    std::vector<Barrier> final;
    std::vector<bool> skipped;  // per pass
  };
  const Plan& currentPlan();

 private:
  struct AccessDecl {
    ResourceId id;
    State state;
  };
  struct Pass {
    std::string name;
    PassFn fn;
    std::vector<AccessDecl> accesses;
    bool sideEffect = false;
    bool culled = false;
    std::function<bool()> enabled;  // null: every frame
  };
  struct Resource {
    std::string name;
    bool isImage = false;
    bool imported = false;
    bool output = false;
    BufferInfo bufferInfo;
    ImageDesc imageDesc;
    State initial, final;
    // Bound or created handles.
    VkBuffer buffer = VK_NULL_HANDLE;
    Image image;
    Buffer ownedBuffer;
    bool owned = false;
  };
  void addAccess(uint32_t pass, ResourceId id, State s);
  // Barriers of the schedule `steps` (passes already placed) with the accesses of the passes in
  // `skip` left out: steps[i].barriers and `fin` are filled.
  void planBarriers(const std::vector<bool>& skip, std::vector<Step>& steps, std::vector<Barrier>& fin) const;

  std::vector<Pass> passes_;
  std::vector<Resource> resources_;
  std::vector<Step> steps_;
  std::vector<Barrier> final_;
  Plan full_;                              // every pass enabled (steps_/final_)
  std::vector<Plan> conditionalPlans_;     // other combinations seen by record()
  bool compiled_ = false;
  Device* device_ = nullptr;
  std::string error_;  // first declaration error, reported by compile()
};

}  // namespace canopy::rg
