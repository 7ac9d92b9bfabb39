/* Convenience: the whole BE-SLAM plugin ABI in one include. */
#ifndef BESLAM_PLUGIN_H
#define BESLAM_PLUGIN_H
#include "beslam/abi.h"
#include "beslam/data.h"
#include "beslam/kinds/backend.h"
#include "beslam/kinds/detector.h"
#include "beslam/kinds/mask_generator.h"
#include "beslam/kinds/motion_checker.h"
#include "beslam/kinds/reconstructor.h"
#endif
