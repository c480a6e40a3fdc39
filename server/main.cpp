#include <cstdio>
int main() { std::puts("voxd"); return 0; }
