int hostValue() { return 1; }
