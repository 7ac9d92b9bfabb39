// Everything a plugin author needs: the five kind base classes, config, views, export macro.
#pragma once
#include "beslam/sdk/backend.hpp"
#include "beslam/sdk/detector.hpp"
#include "beslam/sdk/mask_generator.hpp"
#include "beslam/sdk/motion_checker.hpp"
#include "beslam/sdk/reconstructor.hpp"
