int coreValue() { return 2; }
