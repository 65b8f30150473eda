// image_dump IMAGE: writes "W H C\n" and then the pixels as little-endian float32 (row
// major, top row first, C channels each) to stdout, read with OpenImageIO, so the shell
// tests can check lssview's EXR values in python.
#include <cstdio>
#include <memory>
#include <vector>

#include <OpenImageIO/imageio.h>

int main(int argc, char **argv)
{
    if (argc != 2) {
        std::fprintf(stderr, "usage: image_dump IMAGE\n");
        return 2;
    }
    std::unique_ptr<OIIO::ImageInput> in = OIIO::ImageInput::open(argv[1]);
    if (!in) {
        std::fprintf(stderr, "image_dump: %s\n", OIIO::geterror().c_str());
        return 1;
    }
    const OIIO::ImageSpec &s = in->spec();
    std::vector<float> px((size_t)s.width * (size_t)s.height * (size_t)s.nchannels);
    if (!in->read_image(0, 0, 0, s.nchannels, OIIO::TypeDesc::FLOAT, px.data())) {
        std::fprintf(stderr, "image_dump: %s\n", in->geterror().c_str());
        return 1;
    }
    std::printf("%d %d %d\n", s.width, s.height, s.nchannels);
    std::fflush(stdout);
    std::fwrite(px.data(), sizeof(float), px.size(), stdout);
    return 0;
}
