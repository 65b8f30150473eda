/* lsqt-cl merge: adds the parts of one run (shards) into one LSS and writes its RAW. */
#ifndef LSQT_MERGE_H
#define LSQT_MERGE_H

#ifdef __cplusplus
extern "C" {
#endif

/* argv[0] is "merge"; prog names the command in messages. Returns the exit status. */
int lsqt_merge_main(const char *prog, int argc, char **argv);

#ifdef __cplusplus
}
#endif
#endif
