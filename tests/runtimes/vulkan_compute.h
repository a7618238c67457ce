/* vulkan_compute.h - just enough Vulkan to run one compute shader over buffers and textures and
 * read the buffers back: what the HLSL runtime's tests (test_hlsl_vulkan.c) drive Mesa's lavapipe
 * with. Everything host-visible and in VK_IMAGE_LAYOUT_GENERAL: simple, and the speed is not
 * what is measured. Functions fail the calling cmocka test on any Vulkan error. */
#ifndef CB_VULKAN_COMPUTE_H
#define CB_VULKAN_COMPUTE_H

#include <dlfcn.h>
#include <glob.h>
#include <stdio.h>
#include <vulkan/vulkan.h>

#define VKC_CHECK(call)                                                                                                \
    do {                                                                                                               \
        VkResult vkc_r = (call);                                                                                       \
        if (vkc_r != VK_SUCCESS) fail_msg("%s: VkResult %d", #call, (int)vkc_r);                                       \
    } while (0)

typedef struct vkc_context {
    VkInstance instance;
    VkPhysicalDevice physical;
    VkDevice device;
    VkQueue queue;
    uint32_t family;
    VkCommandPool pool;
    VkPhysicalDeviceMemoryProperties memory;
    char name[VK_MAX_PHYSICAL_DEVICE_NAME_SIZE];
} vkc_context;

/* A buffer or an image with its memory (host-visible: buffers are mapped to fill and read). */
typedef struct vkc_resource {
    VkBuffer buffer;
    VkImage image;
    VkImageView view;
    VkSampler sampler;
    VkDeviceMemory memory;
    VkDeviceSize size;
    VkDescriptorType type;
} vkc_resource;

/* Points the Vulkan loader at Mesa's lavapipe (the software driver the tests are written for) when
 * it is installed and the caller has not chosen a driver: the results then do not depend on
 * whichever GPU the machine has. */
static inline void vkc_prefer_lavapipe(void)
{
    if (getenv("VK_ICD_FILENAMES") || getenv("VK_DRIVER_FILES")) return;
    glob_t g;
    if (glob("/usr/share/vulkan/icd.d/lvp_icd.*.json", 0, NULL, &g) == 0 && g.gl_pathc > 0) {
        setenv("VK_ICD_FILENAMES", g.gl_pathv[0], 1);
        setenv("VK_DRIVER_FILES", g.gl_pathv[0], 1);
        /* The driver stays mapped after vkDestroyInstance, so that LeakSanitizer can name the few
         * bytes lavapipe keeps (tests/lsan.supp) instead of an unknown module. */
        dlopen("libvulkan_lvp.so", RTLD_LAZY | RTLD_NODELETE);
    }
    globfree(&g);
}

/* Creates an instance and a device with a compute queue. false (and the reason in why) when the
 * machine has no Vulkan device at all. */
static inline bool vkc_init(vkc_context *c, char *why, size_t why_size)
{
    memset(c, 0, sizeof *c);
    vkc_prefer_lavapipe();
    VkApplicationInfo app = {.sType = VK_STRUCTURE_TYPE_APPLICATION_INFO, .pApplicationName = "crowdbake tests",
                             .apiVersion = VK_API_VERSION_1_1};
    VkInstanceCreateInfo ici = {.sType = VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO, .pApplicationInfo = &app};
    VkResult r = vkCreateInstance(&ici, NULL, &c->instance);
    if (r != VK_SUCCESS) {
        snprintf(why, why_size, "vkCreateInstance failed (VkResult %d): no Vulkan driver installed", (int)r);
        return false;
    }
    uint32_t n = 1;
    r = vkEnumeratePhysicalDevices(c->instance, &n, &c->physical);
    if ((r != VK_SUCCESS && r != VK_INCOMPLETE) || n == 0) {
        snprintf(why, why_size, "no Vulkan device (install mesa-vulkan-drivers for lavapipe)");
        vkDestroyInstance(c->instance, NULL);
        return false;
    }
    VkPhysicalDeviceProperties props;
    vkGetPhysicalDeviceProperties(c->physical, &props);
    snprintf(c->name, sizeof c->name, "%s", props.deviceName);
    vkGetPhysicalDeviceMemoryProperties(c->physical, &c->memory);
    VkQueueFamilyProperties families[16];
    uint32_t nf = 16;
    vkGetPhysicalDeviceQueueFamilyProperties(c->physical, &nf, families);
    for (c->family = 0; c->family < nf && !(families[c->family].queueFlags & VK_QUEUE_COMPUTE_BIT); ++c->family) {}
    if (c->family == nf) fail_msg("Vulkan device %s has no compute queue", c->name);
    float priority = 1;
    VkDeviceQueueCreateInfo qci = {.sType = VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO, .queueFamilyIndex = c->family,
                                   .queueCount = 1, .pQueuePriorities = &priority};
    VkDeviceCreateInfo dci = {.sType = VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO, .queueCreateInfoCount = 1, .pQueueCreateInfos = &qci};
    VKC_CHECK(vkCreateDevice(c->physical, &dci, NULL, &c->device));
    vkGetDeviceQueue(c->device, c->family, 0, &c->queue);
    VkCommandPoolCreateInfo pci = {.sType = VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO, .queueFamilyIndex = c->family};
    VKC_CHECK(vkCreateCommandPool(c->device, &pci, NULL, &c->pool));
    return true;
}

static inline void vkc_free_context(vkc_context *c)
{
    vkDestroyCommandPool(c->device, c->pool, NULL);
    vkDestroyDevice(c->device, NULL);
    vkDestroyInstance(c->instance, NULL);
}

/* A test group's fixture: opens the device once, or says why `what` cannot run here (the tests then skip). */
static inline bool vkc_open_for_tests(vkc_context *c, const char *what)
{
    char why[256];
    bool opened = vkc_init(c, why, sizeof why);
    if (opened) printf("  Vulkan on %s\n", c->name);
    else printf("  SKIPPED: %s: %s cannot be run here\n", why, what);
    return opened;
}

/* A test program's device, shared by its cases: defines `vk` and `have_device`, and the group's
 * `setup` (vkc_open_for_tests: where none opens, the cases skip) and `teardown` for
 * cmocka_run_group_tests_name. `what` names what the program runs, for the line saying why not. */
#define VKC_TEST_DEVICE(what)                                                                                          \
    static vkc_context vk;                                                                                             \
    static bool have_device;                                                                                           \
    static int setup(void **state)                                                                                     \
    {                                                                                                                  \
        (void)state;                                                                                                   \
        have_device = vkc_open_for_tests(&vk, what);                                                                   \
        return 0;                                                                                                      \
    }                                                                                                                  \
    static int teardown(void **state)                                                                                  \
    {                                                                                                                  \
        (void)state;                                                                                                   \
        if (have_device) vkc_free_context(&vk);                                                                        \
        return 0;                                                                                                      \
    }

static inline VkDeviceMemory vkc_allocate(vkc_context *c, VkMemoryRequirements req)
{
    VkMemoryPropertyFlags want = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
    uint32_t type = 0;
    while (type < c->memory.memoryTypeCount &&
           !((req.memoryTypeBits & (1u << type)) && (c->memory.memoryTypes[type].propertyFlags & want) == want))
        ++type;
    if (type == c->memory.memoryTypeCount) fail_msg("no host-visible memory on %s", c->name);
    VkMemoryAllocateInfo mai = {.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO, .allocationSize = req.size, .memoryTypeIndex = type};
    VkDeviceMemory m;
    VKC_CHECK(vkAllocateMemory(c->device, &mai, NULL, &m));
    return m;
}

/* A host-visible buffer of `size` bytes, filled from data (or zeroed): a storage or uniform buffer. */
static inline vkc_resource vkc_buffer(vkc_context *c, VkDescriptorType type, const void *data, VkDeviceSize size)
{
    vkc_resource b = {.size = size, .type = type};
    VkBufferCreateInfo bci = {.sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO, .size = size,
                              .usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT |
                                       VK_BUFFER_USAGE_TRANSFER_SRC_BIT,
                              .sharingMode = VK_SHARING_MODE_EXCLUSIVE};
    VKC_CHECK(vkCreateBuffer(c->device, &bci, NULL, &b.buffer));
    VkMemoryRequirements req;
    vkGetBufferMemoryRequirements(c->device, b.buffer, &req);
    b.memory = vkc_allocate(c, req);
    VKC_CHECK(vkBindBufferMemory(c->device, b.buffer, b.memory, 0));
    void *map;
    VKC_CHECK(vkMapMemory(c->device, b.memory, 0, size, 0, &map));
    if (data) memcpy(map, data, size);
    else memset(map, 0, size);
    vkUnmapMemory(c->device, b.memory);
    return b;
}

static inline void vkc_read(vkc_context *c, const vkc_resource *b, void *out)
{
    void *map;
    VKC_CHECK(vkMapMemory(c->device, b->memory, 0, b->size, 0, &map));
    memcpy(out, map, b->size);
    vkUnmapMemory(c->device, b->memory);
}

static inline VkCommandBuffer vkc_begin(vkc_context *c)
{
    VkCommandBufferAllocateInfo cai = {.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO, .commandPool = c->pool,
                                       .level = VK_COMMAND_BUFFER_LEVEL_PRIMARY, .commandBufferCount = 1};
    VkCommandBuffer cmd;
    VKC_CHECK(vkAllocateCommandBuffers(c->device, &cai, &cmd));
    VkCommandBufferBeginInfo bi = {.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO,
                                   .flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT};
    VKC_CHECK(vkBeginCommandBuffer(cmd, &bi));
    return cmd;
}

/* Ends, submits and waits for cmd (a fence: the results are there when this returns). */
static inline void vkc_submit(vkc_context *c, VkCommandBuffer cmd)
{
    VKC_CHECK(vkEndCommandBuffer(cmd));
    VkFenceCreateInfo fci = {.sType = VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    VkFence fence;
    VKC_CHECK(vkCreateFence(c->device, &fci, NULL, &fence));
    VkSubmitInfo si = {.sType = VK_STRUCTURE_TYPE_SUBMIT_INFO, .commandBufferCount = 1, .pCommandBuffers = &cmd};
    VKC_CHECK(vkQueueSubmit(c->queue, 1, &si, fence));
    VKC_CHECK(vkWaitForFences(c->device, 1, &fence, VK_TRUE, UINT64_MAX));
    vkDestroyFence(c->device, fence, NULL);
    vkFreeCommandBuffers(c->device, c->pool, 1, &cmd);
}

/* Everything before the barrier (transfers, shader writes) visible to everything after it. */
static inline void vkc_barrier(VkCommandBuffer cmd)
{
    VkMemoryBarrier mb = {.sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER,
                          .srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT | VK_ACCESS_SHADER_WRITE_BIT,
                          .dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_HOST_READ_BIT};
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT | VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                         VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &mb, 0, NULL, 0, NULL);
}

/* A 2D texture of width x height texels of `format` (texel_bytes each), filled from data when
 * given, in GENERAL layout: sampled (Texture2D) or, with storage, also written (RWTexture2D). */
static inline vkc_resource vkc_image(vkc_context *c, VkFormat format, uint32_t width, uint32_t height, size_t texel_bytes,
                                     const void *data, bool storage)
{
    vkc_resource t = {.type = storage ? VK_DESCRIPTOR_TYPE_STORAGE_IMAGE : VK_DESCRIPTOR_TYPE_SAMPLED_IMAGE};
    VkImageCreateInfo ici = {.sType = VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO, .imageType = VK_IMAGE_TYPE_2D, .format = format,
                             .extent = {width, height, 1}, .mipLevels = 1, .arrayLayers = 1,
                             .samples = VK_SAMPLE_COUNT_1_BIT, .tiling = VK_IMAGE_TILING_OPTIMAL,
                             .usage = VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT |
                                      (storage ? VK_IMAGE_USAGE_STORAGE_BIT : 0),
                             .initialLayout = VK_IMAGE_LAYOUT_UNDEFINED};
    VKC_CHECK(vkCreateImage(c->device, &ici, NULL, &t.image));
    VkMemoryRequirements req;
    vkGetImageMemoryRequirements(c->device, t.image, &req);
    t.memory = vkc_allocate(c, req);
    VKC_CHECK(vkBindImageMemory(c->device, t.image, t.memory, 0));
    VkImageViewCreateInfo vci = {.sType = VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO, .image = t.image,
                                 .viewType = VK_IMAGE_VIEW_TYPE_2D, .format = format,
                                 .subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1}};
    VKC_CHECK(vkCreateImageView(c->device, &vci, NULL, &t.view));
    size_t bytes = (size_t)width * height * texel_bytes;
    vkc_resource staging = vkc_buffer(c, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, data, bytes ? bytes : 16);
    VkCommandBuffer cmd = vkc_begin(c);
    VkImageMemoryBarrier ib = {.sType = VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER, .dstAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT,
                               .oldLayout = VK_IMAGE_LAYOUT_UNDEFINED, .newLayout = VK_IMAGE_LAYOUT_GENERAL,
                               .srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED, .dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED,
                               .image = t.image, .subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1}};
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 0, NULL, 0, NULL, 1, &ib);
    VkBufferImageCopy region = {.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1}, .imageExtent = {width, height, 1}};
    vkCmdCopyBufferToImage(cmd, staging.buffer, t.image, VK_IMAGE_LAYOUT_GENERAL, 1, &region);
    vkc_barrier(cmd);
    vkc_submit(c, cmd);
    vkDestroyBuffer(c->device, staging.buffer, NULL);
    vkFreeMemory(c->device, staging.memory, NULL);
    return t;
}

/* A nearest-filtering sampler (Unreal's Custom node hands each texture's sampler to the code). */
static inline vkc_resource vkc_sampler(vkc_context *c)
{
    vkc_resource s = {.type = VK_DESCRIPTOR_TYPE_SAMPLER};
    VkSamplerCreateInfo sci = {.sType = VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO, .magFilter = VK_FILTER_NEAREST,
                               .minFilter = VK_FILTER_NEAREST, .addressModeU = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE,
                               .addressModeV = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE,
                               .addressModeW = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE};
    VKC_CHECK(vkCreateSampler(c->device, &sci, NULL, &s.sampler));
    return s;
}

static inline void vkc_free(vkc_context *c, vkc_resource *r)
{
    if (r->sampler) vkDestroySampler(c->device, r->sampler, NULL);
    if (r->view) vkDestroyImageView(c->device, r->view, NULL);
    if (r->image) vkDestroyImage(c->device, r->image, NULL);
    if (r->buffer) vkDestroyBuffer(c->device, r->buffer, NULL);
    if (r->memory) vkFreeMemory(c->device, r->memory, NULL);
    memset(r, 0, sizeof *r);
}

/* A compute pipeline of one SPIR-V module ("main") whose bindings 0..n-1 of set 0 are `resources`. */
typedef struct vkc_pipeline {
    VkDescriptorSetLayout set_layout;
    VkPipelineLayout layout;
    VkPipeline pipeline;
    VkDescriptorPool pool;
    VkDescriptorSet set;
} vkc_pipeline;

static inline vkc_pipeline vkc_compute(vkc_context *c, const uint32_t *spirv, size_t spirv_bytes, const vkc_resource *resources,
                                       uint32_t n)
{
    vkc_pipeline p;
    VkDescriptorSetLayoutBinding b[16];
    VkDescriptorPoolSize sizes[16];
    for (uint32_t i = 0; i < n; ++i) {
        b[i] = (VkDescriptorSetLayoutBinding){i, resources[i].type, 1, VK_SHADER_STAGE_COMPUTE_BIT, NULL};
        sizes[i] = (VkDescriptorPoolSize){resources[i].type, 1};
    }
    VkDescriptorSetLayoutCreateInfo dli = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO, .bindingCount = n, .pBindings = b};
    VKC_CHECK(vkCreateDescriptorSetLayout(c->device, &dli, NULL, &p.set_layout));
    VkPipelineLayoutCreateInfo pli = {.sType = VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO, .setLayoutCount = 1,
                                      .pSetLayouts = &p.set_layout};
    VKC_CHECK(vkCreatePipelineLayout(c->device, &pli, NULL, &p.layout));
    VkShaderModuleCreateInfo smi = {.sType = VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO, .codeSize = spirv_bytes, .pCode = spirv};
    VkShaderModule module;
    VKC_CHECK(vkCreateShaderModule(c->device, &smi, NULL, &module));
    VkComputePipelineCreateInfo cpi = {.sType = VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO,
                                       .stage = {.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO,
                                                 .stage = VK_SHADER_STAGE_COMPUTE_BIT, .module = module, .pName = "main"},
                                       .layout = p.layout};
    VKC_CHECK(vkCreateComputePipelines(c->device, VK_NULL_HANDLE, 1, &cpi, NULL, &p.pipeline));
    vkDestroyShaderModule(c->device, module, NULL);
    VkDescriptorPoolCreateInfo dpi = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO, .maxSets = 1, .poolSizeCount = n,
                                      .pPoolSizes = sizes};
    VKC_CHECK(vkCreateDescriptorPool(c->device, &dpi, NULL, &p.pool));
    VkDescriptorSetAllocateInfo dsi = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO, .descriptorPool = p.pool,
                                       .descriptorSetCount = 1, .pSetLayouts = &p.set_layout};
    VKC_CHECK(vkAllocateDescriptorSets(c->device, &dsi, &p.set));
    for (uint32_t i = 0; i < n; ++i) {
        VkDescriptorBufferInfo bi = {resources[i].buffer, 0, VK_WHOLE_SIZE};
        VkDescriptorImageInfo ii = {resources[i].sampler, resources[i].view, VK_IMAGE_LAYOUT_GENERAL};
        bool image = resources[i].image || resources[i].sampler;
        VkWriteDescriptorSet w = {.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, .dstSet = p.set, .dstBinding = i,
                                  .descriptorCount = 1, .descriptorType = resources[i].type,
                                  .pImageInfo = image ? &ii : NULL, .pBufferInfo = image ? NULL : &bi};
        vkUpdateDescriptorSets(c->device, 1, &w, 0, NULL);
    }
    return p;
}

/* Records a dispatch of `groups` workgroups (x) into cmd, then a barrier. */
static inline void vkc_dispatch(VkCommandBuffer cmd, const vkc_pipeline *p, uint32_t groups)
{
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, p->pipeline);
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, p->layout, 0, 1, &p->set, 0, NULL);
    vkCmdDispatch(cmd, groups, 1, 1);
    vkc_barrier(cmd);
}

static inline void vkc_free_pipeline(vkc_context *c, vkc_pipeline *p)
{
    vkDestroyDescriptorPool(c->device, p->pool, NULL);
    vkDestroyPipeline(c->device, p->pipeline, NULL);
    vkDestroyPipelineLayout(c->device, p->layout, NULL);
    vkDestroyDescriptorSetLayout(c->device, p->set_layout, NULL);
}

#endif
