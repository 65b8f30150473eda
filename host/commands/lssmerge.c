/* lssmerge OUT.lss IN.lss...: the same as lsqt-cl merge (host/commands/merge.c). */
#include "lsqt/merge.h"

int main(int argc, char **argv)
{
    return lsqt_merge_main("lssmerge", argc, argv);
}
