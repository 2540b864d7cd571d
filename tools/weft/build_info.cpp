#include "build_info.h"

// tools/CMakeLists.txt defines these; the fallbacks keep the file compilable on its own.
#ifndef WEFT_VERSION
#define WEFT_VERSION "unknown"
#endif
#ifndef WEFT_BUILD_TYPE
#define WEFT_BUILD_TYPE ""
#endif
#ifndef WEFT_SOURCE_DIR
#define WEFT_SOURCE_DIR ""
#endif
#ifndef WEFT_HAVE_CUDA
#define WEFT_HAVE_CUDA 0
#endif
#ifndef WEFT_HAVE_RENDER
#define WEFT_HAVE_RENDER 0
#endif
#ifndef WEFT_HAVE_EDITOR
#define WEFT_HAVE_EDITOR 0
#endif
#ifndef WEFT_HAVE_ASSETS
#define WEFT_HAVE_ASSETS 0
#endif

namespace weft::cli {

const BuildInfo& build_info() {
    static const BuildInfo info{
        .version = WEFT_VERSION,
        .build_type = WEFT_BUILD_TYPE,
        .source_dir = WEFT_SOURCE_DIR,
        .cuda = WEFT_HAVE_CUDA != 0,
        .render = WEFT_HAVE_RENDER != 0,
        .editor = WEFT_HAVE_EDITOR != 0,
        .assets = WEFT_HAVE_ASSETS != 0,
    };
    return info;
}

}  // namespace weft::cli
