#include "relight/vision.hpp"

#include "core/module.hpp"

namespace rfd::relight {

const Vision& vision() {
    static const Vision& loaded = load_module<const Vision>("opencv", "rfd_opencv_vision");
    return loaded;
}

}  // namespace rfd::relight
