#pragma once
/// @file
/// The one exception type of the public API. User-input problems (scene files, meshes, parameters)
/// throw it at load time with a message that names the file, line and key or value at fault;
/// `step()` never throws for numerical trouble, it reports it in `StepStats`.

#include <stdexcept>
#include <string>

namespace weft {

class Error : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

}  // namespace weft
