int pluginValue() { return 3; }
