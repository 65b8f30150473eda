/* lssinfo FILE.lss [--json PATH]: the same as lsqt-cl info (host/commands/info.c). */
#include "lsqt/info.h"

int main(int argc, char **argv)
{
    return lsqt_info_main("lssinfo", argc, argv);
}
