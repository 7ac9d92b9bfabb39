// beslam::Error and throwAt live in the SDK's formats component (beslam/formats/error.hpp), so the host
// and plugins throw one type; the CLI prints its message as the single error line a user sees.
// Exceptions never leave the host through the C ABI.
#pragma once

#include "beslam/formats/error.hpp"
