/* lssmerge OUT.lss IN.lss...: the same as lsqt-cl merge (host/merge.c). */
#include "lsqt/merge.h"

int main(int argc, char **argv)
{
    return lsqt_merge_main("lssmerge", argc, argv);
}
