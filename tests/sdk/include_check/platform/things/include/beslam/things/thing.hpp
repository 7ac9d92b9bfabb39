// A host module's header in the fixture tree of plugins_include_check_refuses_host_header.
#pragma once
