/* Making packings visible: `capdem export` (XDMF description of a run file
 * for ParaView / VisIt) and `capdem render` (a PNG drawn with matplotlib).
 * docs/visualization.md describes both. */
#ifndef CAPDEM_EXPORT_H
#define CAPDEM_EXPORT_H

/* capdem export RUN.h5 [-o OUT.xmf]
 * argv[0] is the run file (argc counts the arguments after `export`).
 * Writes RUN.xmf next to the run file: an XDMF file whose data items point
 * into the run file, through small helper datasets (connectivity, and virtual
 * datasets that select one snapshot) written once under /visualization.
 * Returns the exit status: 0 success, 2 bad input, 1 other failure. */
int cd_cmd_export(int argc, char **argv);

/* capdem render RUN.h5 [--snapshot N] -o PICTURE.png [--mode arms|forces] ...
 * Runs host/render.py with /usr/bin/python3 (matplotlib, h5py, numpy from
 * Debian) and returns its exit status: 0 success, 2 bad input or a missing
 * Python module, 1 other failure. */
int cd_cmd_render(int argc, char **argv);

#endif
