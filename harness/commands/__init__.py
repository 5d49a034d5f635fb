"""The subcommands of `torquebench`, one module each (harness.cli imports only the one run).

SUMMARY: each command's one-line help, here so that `torquebench --help` lists them
without importing any command's libraries.
"""

SUMMARY = {
    "bench": "run every stage on one robot and write a report",
    "closeloop": "residual -> missing effect -> add it -> error before/after",
    "excite": "design a rest-to-rest excitation for identification (CSV)",
    "export": "write an identified model's bodies into the robot's file",
    "generate": "torque data from MuJoCo (inverse dynamics or measured)",
    "identify": "identify a sparse torque model from data",
    "ingest": "a measured log (CSV) into a dataset .npz",
    "plan": "energy-optimal trajectory avoiding a moving obstacle",
    "predict": "torques of a model (MODEL.json or 'pinocchio') on data",
    "replay": "execute a planned trajectory in MuJoCo and measure energy, clearance, tracking",
    "robots": "list the registered robots and example-robot-data's URDFs, each checked",
    "study": "run one long study on demand and write its report",
    "sweep": "identification error over a grid of robots, noise levels, seeds, methods and "
             "sample counts, on Ray",
}


def add_chain_option(parser) -> None:
    """--chain, beside every --robot: the arm between two links of a whole robot's URDF."""
    parser.add_argument(
        "--chain", default=None, metavar="BASE_LINK:TIP_LINK",
        help="the arm between two links of a whole robot's URDF (a torso and two arms: "
        "torso_link:arm_left_7_link); every other joint held fixed at 0, or at its nearest "
        "limit when 0 is outside them, or where --hold says (said in the model's robot record, "
        "'held'); recorded with the data and the model, so later commands find it")
    parser.add_argument(
        "--hold", default=None, metavar="JOINT=POSITION[,...]",
        help="with --chain: the positions (rad, or m for a prismatic joint) some held joints "
        "are held at, within their limits (torso_lift_joint=0.2)")


def chain_option(args) -> str | None:
    """--chain with --hold's positions (harness.robots.subchain's BASE:TIP@JOINT=POSITION,...);
    None without --chain."""
    if getattr(args, "hold", None) and not args.chain:
        from harness.errors import UserError

        raise UserError("--hold holds joints off a --chain: give --chain BASE_LINK:TIP_LINK")
    return args.chain and (f"{args.chain}@{args.hold}" if args.hold else args.chain)
