#!/usr/bin/python3
"""Validation studies of docs/validation.md: runs, analysis, tables, figures.

usage:
  host/validate.py study1 [--build build] [--out runs/validation]
                          [--alphas 3,9,1,1.5,2,5,7] [--seeds 1,2] [--n 1000]
                          [--friction-alphas 3,9] [--friction-mu 0.4]
                          [--threads 2] [--jobs 1] [--max-steps 20000000]
                          [--no-run] [--wait] [--figures DIR] [--markdown] [--check] [--ci] [--fresh]
  host/validate.py study2|study3|study4 [--build build] [--out runs/validation] [--psis ...] [--seeds 1,2]
                          [--n N] [--plan] [--no-run] [--figures DIR] [--records DIR]
                          (host/validate_deposit.py)


Study 1 is host/validate_study1.py, studies 2-4 host/validate_deposit.py;
both run their cases through host/validate_runs.py (run or resume, lock,
timing).  Everything is resumable: run the same command again and it skips
what is done, resumes what was interrupted and analyses what is new.
"""
import argparse
import sys

sys.dont_write_bytecode = True  # no host/__pycache__ in the worktree


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = ap.add_subparsers(dest="study", required=True)
    p1 = sub.add_parser("study1", help="hexapods under radial compaction (Tran et al. 2024)")
    p1.add_argument("--build", default="build", help="build folder holding capdem")
    p1.add_argument("--out", default="runs/validation", help="output folder (runs under OUT/study1)")
    p1.add_argument("--alphas", default="3,9,1,1.5,2,5,7", help="frictionless aspect ratios, in run order")
    p1.add_argument("--seeds", default="1,2")
    p1.add_argument("--n", type=int, default=1000, help="particles per run")
    p1.add_argument("--friction-alphas", default="3,9", help="aspect ratios repeated at --friction-mu ('' for none)")
    p1.add_argument("--friction-mu", type=float, default=0.4)
    p1.add_argument("--threads", type=int, default=2, help="OpenMP threads of each capdem run")
    p1.add_argument("--jobs", type=int, default=1, help="runs at a time")
    p1.add_argument("--steps", type=int, default=5000000, help="first step cap (the presets')")
    p1.add_argument("--max-steps", type=int, default=20000000, help="largest cap a resume may set")
    p1.add_argument("--no-run", action="store_true", help="only collect finished cases")
    p1.add_argument("--wait", action="store_true",
                    help="wait for a case another process is running (a capdem left by a killed driver) "
                         "instead of skipping it, so that one simulation runs at a time")
    p1.add_argument("--reanalyse", action="store_true", help="run capdem analyze again on finished cases")
    p1.add_argument("--fresh", action="store_true", help="delete the selected cases' folders first")
    p1.add_argument("--figures", help="write the PNG figures into this folder")
    p1.add_argument("--markdown", action="store_true", help="also print the table as Markdown")
    p1.add_argument("--markdown-into", metavar="FILE[:MARKER]",
                    help="write the table between <!-- MARKER:begin/end --> of FILE (default marker: STUDY-table)")
    p1.add_argument("--check", action="store_true", help="assert the smoke test's bands (exit 1 if not)")
    p1.add_argument("--ci", action="store_true",
                    help="the CI presets' relaxation check (energy steady to 1e-3 every 2000 steps, not 1e-4 "
                         "every 5000); case folders get a _ci suffix")
    for name, what in (("study2", "2D crosses, deposit and compress (Conzelmann et al.)"),
                       ("study3", "3D stars in a cylinder, deposit and compress (Conzelmann et al.)"),
                       ("study4", "spheres in the 2D box and the cylinder (Conzelmann et al., Mueth)")):
        p = sub.add_parser(name, help=what)
        p.add_argument("--build", default="build", help="build folder holding capdem")
        p.add_argument("--out", default="runs/validation", help="output folder (runs under OUT/%s)" % name)
        if name != "study4":
            p.add_argument("--psis", default="", help="sphericities of Table S1 (default: the issue's four)")
        p.add_argument("--seeds", default="1,2")
        p.add_argument("--n", type=int, default=0, help="particles per run (default: the paper's count rule)")
        p.add_argument("--width-l", type=float, default=0,
                       help="box width / cylinder diameter in L (default: the study's; smaller only for tests)")
        p.add_argument("--threads", type=int, default=2)
        p.add_argument("--steps", type=int, default=5000000)
        p.add_argument("--max-steps", type=int, default=40000000)
        p.add_argument("--plan", action="store_true", help="print the cases (count, size, dt) and stop")
        p.add_argument("--no-run", action="store_true")
        p.add_argument("--reanalyse", action="store_true")
        p.add_argument("--figures", help="write the PNG figures into this folder")
        p.add_argument("--records", default="",
                       help="folder of the runs' records (docs/validation_runs): each finished run's table row "
                            "is written there, and a case whose run folder is not in --out is read from it")
        p.add_argument("--markdown", action="store_true", help="also print the table as Markdown")
        p.add_argument("--markdown-into", metavar="FILE[:MARKER]",
                       help="write the table between <!-- MARKER:begin/end --> of FILE (default marker: STUDY-table)")
    args = ap.parse_args()
    if args.study == "study1":
        import validate_study1
        return validate_study1.study1(args)
    import validate_deposit
    return validate_deposit.run_study(args)


if __name__ == "__main__":
    sys.exit(main())
