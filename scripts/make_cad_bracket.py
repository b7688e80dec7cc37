"""Writes data/cad-bracket/bracket.step, the STEP model the README tour and the tests compare
scans with: a 60 × 40 × 20 mm block, its four vertical edges rounded to R5, a Ø16 mm hole through
it along z and a Ø8 mm hole across it along x (planes, cylinders and fillet surfaces meeting at
convex and concave edges). Needs OpenCASCADE's Python binding (pip install machscan[cad]).

    python scripts/make_cad_bracket.py
"""

from __future__ import annotations

from pathlib import Path

from OCP.BRepAdaptor import BRepAdaptor_Curve
from OCP.BRepAlgoAPI import BRepAlgoAPI_Cut
from OCP.BRepFilletAPI import BRepFilletAPI_MakeFillet
from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox, BRepPrimAPI_MakeCylinder
from OCP.GeomAbs import GeomAbs_Line
from OCP.gp import gp_Ax2, gp_Dir, gp_Pnt
from OCP.IFSelect import IFSelect_RetDone
from OCP.STEPControl import STEPControl_AsIs, STEPControl_Writer
from OCP.TopAbs import TopAbs_EDGE
from OCP.TopExp import TopExp_Explorer
from OCP.TopoDS import TopoDS

OUT = Path(__file__).resolve().parent.parent / "data" / "cad-bracket" / "bracket.step"


def bracket():
    block = BRepPrimAPI_MakeBox(gp_Pnt(-30, -20, 0), 60.0, 40.0, 20.0).Shape()
    fillet = BRepFilletAPI_MakeFillet(block)
    edges = TopExp_Explorer(block, TopAbs_EDGE)
    to_edge = getattr(TopoDS, "Edge_s", None) or TopoDS.Edge
    while edges.More():
        edge = to_edge(edges.Current())
        curve = BRepAdaptor_Curve(edge)
        if curve.GetType() == GeomAbs_Line and abs(curve.Line().Direction().Z()) > 0.99:
            fillet.Add(5.0, edge)
        edges.Next()
    shape = fillet.Shape()
    down = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0, 0, -1), gp_Dir(0, 0, 1)), 8.0, 22.0).Shape()
    shape = BRepAlgoAPI_Cut(shape, down).Shape()
    across = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(-31, 0, 10), gp_Dir(1, 0, 0)), 4.0, 62.0).Shape()
    return BRepAlgoAPI_Cut(shape, across).Shape()


def main() -> None:
    writer = STEPControl_Writer()
    writer.Transfer(bracket(), STEPControl_AsIs)
    OUT.parent.mkdir(parents=True, exist_ok=True)
    assert writer.Write(str(OUT)) == IFSelect_RetDone
    print(f"written {OUT}")


if __name__ == "__main__":
    main()
