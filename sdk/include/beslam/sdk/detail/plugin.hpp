// C-to-C++ glue shared by every kind (included by plugin.hpp): frame conversion, the noexcept guard
// that turns C++ exceptions into status codes, the instance wrapper, call() which every kind's table
// function goes through, and the descriptor builder. Each kind's detail/<kind>.hpp builds its C function
// table from these: each function converts the C views, calls the plugin through call() (exceptions
// become a status) and keeps what it returns in storage that lives until the next call.
#pragma once

namespace beslam::sdk {

inline Frame toFrame(const beslam_frame* frame) {
  if (frame == nullptr) throw std::invalid_argument("frame is null");
  beslam_frame f{};
  std::memcpy(&f, frame, std::min<size_t>(frame->struct_size, sizeof(f)));
  Frame out;
  out.index = f.index;
  out.timestamp = f.timestamp;
  out.gray = toMat(f.gray);
  out.color = toMat(f.color);
  out.lidar = f.lidar;
  out.image_path = f.image_path ? f.image_path : "";
  return out;
}

namespace detail {

// What every kind base class derives from: its ABI kind. describe() finds the kind's C function table as
// the overload table(Tag<Impl>, const KindBase*) in detail/<kind>.hpp (by argument-dependent lookup, so
// the kind headers may come after this one).
template <class Impl>
struct Tag {};
template <class Base, int32_t K>
struct Kind {
  static constexpr int32_t kKind = K;
};

// The glue's way into a kind's private abi_ buffers (what the host reads until the next call).
struct Access {
  template <class KindBase>
  static auto& buffers(KindBase& kind) {
    return kind.abi_;
  }
};

// A kind's C function table for one plugin class: built once, valid while the library is loaded.
template <class Table, class... Functions>
const void* makeTable(Functions... functions) {
  static const Table table = {sizeof(Table), 0, functions...};
  return &table;
}

// Runs f, mapping every exception to a status and logging its message: nothing crosses the C ABI.
template <class F>
beslam_status guarded(const Context* context, F&& f) noexcept {
  auto report = [context](const char* what) noexcept {
    try {
      if (context) context->log(BESLAM_LOG_ERROR, what);
    } catch (...) {
    }
  };
  try {
    f();
    return BESLAM_OK;
  } catch (const ConfigError& e) {
    report(e.what());
    return BESLAM_ERROR_INVALID_CONFIG;
  } catch (const std::bad_alloc&) {
    report("out of memory");
    return BESLAM_ERROR_OUT_OF_MEMORY;
  } catch (const std::invalid_argument& e) {
    report(e.what());
    return BESLAM_ERROR_INVALID_ARGUMENT;
  } catch (const std::exception& e) {
    report(e.what());
    return BESLAM_ERROR_RUNTIME;
  } catch (...) {
    report("unknown exception");
    return BESLAM_ERROR_INTERNAL;
  }
}

// An instance as the host sees it: the context outlives the plugin object built from it.
template <class Impl>
struct Instance {
  explicit Instance(const beslam_create_info& info, const char* id) : context(info, id) {}
  Context context;
  std::unique_ptr<Impl> impl;
};

// Runs body on the instance's plugin object, seen as its kind, inside guarded().
template <class Impl, class Kind, class Body>
beslam_status call(void* instance, const char* what, Body&& body) noexcept {
  auto* self = static_cast<Instance<Impl>*>(instance);
  return guarded(self ? &self->context : nullptr, [&] {
    if (self == nullptr || !self->impl) throw std::invalid_argument(std::string(what) + ": null instance");
    body(static_cast<Kind&>(*self->impl));
  });
}

// Throws "what: null argument" when a pointer the call writes through is null.
template <class... P>
void require(const char* what, const P*... pointers) {
  if (((pointers == nullptr) || ...)) throw std::invalid_argument(std::string(what) + ": null argument");
}

}  // namespace detail

// The descriptor of plugin class Impl (one per class, built on first use, valid while loaded).
// Impl derives from one kind base (Detector, MotionChecker, ...), which supplies kKind and its table.
template <class Impl>
const beslam_plugin_descriptor* describe(const PluginInfo& info) {
  static const std::string id = info.id;
  static beslam_plugin_descriptor d = [&info] {
    beslam_plugin_descriptor desc{};
    desc.struct_size = sizeof(beslam_plugin_descriptor);
    desc.abi_version = BESLAM_ABI_VERSION;
    desc.id = id.c_str();
    desc.name = info.name;
    desc.description = info.description;
    desc.kind = Impl::kKind;
    desc.version_major = info.version.major;
    desc.version_minor = info.version.minor;
    desc.version_patch = info.version.patch;
    desc.config_fields = info.fields;
    desc.config_field_count = info.field_count;
    desc.config_field_size = sizeof(beslam_config_field);
    desc.create = [](const beslam_create_info* create_info, void** out) -> beslam_status {
      if (create_info == nullptr || out == nullptr) return BESLAM_ERROR_INVALID_ARGUMENT;
      *out = nullptr;
      detail::Instance<Impl>* instance = nullptr;
      try {
        instance = new detail::Instance<Impl>(*create_info, id.c_str());
      } catch (...) {
        return BESLAM_ERROR_OUT_OF_MEMORY;
      }
      const Config config(create_info->config, create_info->config_count);
      const beslam_status status = detail::guarded(
          &instance->context, [&] { instance->impl = std::make_unique<Impl>(instance->context, config); });
      if (status != BESLAM_OK) {
        delete instance;
        return status;
      }
      *out = instance;
      return BESLAM_OK;
    };
    desc.destroy = [](void* instance) {
      try {
        delete static_cast<detail::Instance<Impl>*>(instance);
      } catch (...) {
      }
    };
    desc.functions = table(detail::Tag<Impl>{}, static_cast<const Impl*>(nullptr));
    return desc;
  }();
  return &d;
}

}  // namespace beslam::sdk
