// tinygltf 2.7 (Debian's header) compiled into Canopy's own library: a host links no tinygltf, and
// the test build's sanitizers cover its parser too. Images are decoded by the loader's own
// callback (render/gltf_loader.cpp), never by tinygltf's stb_image copy; nothing is written.
#define TINYGLTF_IMPLEMENTATION


#include <tiny_gltf.h>
