"""Spatial scenes the spatial tests share."""
import numpy as np
import skfem_flex as sf


def spatial_mechanism():
    """Every spatial joint once, under gravity, from rest (a hinge, a ball, a cylinder, a cross joint, a
    rod, a weld, a prismatic guide with a driver)."""
    J = [0.02, 0.09, 0.1]
    A = sf.SpatialRigidBody(1.0, J, position=[0.5, 0, 0], name="A")
    B = sf.SpatialRigidBody(0.8, J, position=[1.0, 0, -0.5], name="B")
    C = sf.SpatialRigidBody(0.5, J, position=[1.0, 0, -0.5], name="C")
    D = sf.SpatialRigidBody(0.6, J, position=[1.0, 0, -1.1], name="D")
    E = sf.SpatialPointMass(0.3, position=[1.0, 0.5, -1.4], name="E")
    F = sf.SpatialRigidBody(0.4, J, position=[1.3, 0, -1.1], name="F")
    G = sf.SpatialRigidBody(0.7, J, position=[-1.0, 0, 0], velocity=[0.3, 0, 0], name="G")    # ṡ(0) = 0.3 m/s
    law = sf.MotionLaw(lambda t: 0.1 * np.sin(3 * t), lambda t: 0.3 * np.cos(3 * t), lambda t: -0.9 * np.sin(3 * t))
    cons = [sf.Revolute3D(A.point([-0.5, 0, 0]), None, axis=(0, 1, 0)),
            sf.Spherical(A.point([0.5, 0, 0]), B.point([0, 0, 0.5])),
            sf.Cylindrical(B.point(), C.point(), axis=(0, 0, 1)),
            sf.Universal(C.point([0, 0, -0.3]), D.point([0, 0, 0.3]), axis_a=(1, 0, 0), axis_b=(0, 1, 0)),
            sf.Distance3D(D.point([0, 0, -0.3]), E.point()),
            sf.Weld3D(D.point([0.15, 0, 0]), F.point([-0.15, 0, 0])),
            sf.Prismatic3D(G.point(), None, axis=(1, 0, 0)),
            sf.TranslationDriver(G.point(), None, axis=(1, 0, 0), law=law)]
    return sf.Scene([A, B, C, D, E, F, G], cons, [sf.Gravity((0, 0, -9.81))], name="spatial mechanism")


def floating_frame_joints():
    """Joints with axes at floating-frame material points against moving bodies (product rows): a clamped
    floating-frame beam, a rigid body on a cylinder at its tip whose slide a driver moves, a second
    floating-frame beam on a cross joint at the body's far end and a rod from its tip to the first beam's
    mid-span; under gravity, from rest (the driver's law starts at rest)."""
    import skfem
    from skfem_flex.bodies.floating_spatial.body import FloatingBeam3D
    from skfem_flex.fem.spatial_beam import TimoshenkoBeam3D

    section = sf.SpatialSection(EA=1e4, GA1=8e3, GA2=6e3, GJ=400.0, EI1=500.0, EI2=300.0, rhoA=1.3, rhoI1=0.02,
                                rhoI2=0.01)
    beam = TimoshenkoBeam3D(skfem.MeshLine(np.linspace(0.0, 2.0, 4)), section, order=1)
    a = FloatingBeam3D(beam, strain="linear", name="A")
    r = sf.SpatialRigidBody(1.0, (0.1, 0.2, 0.25), position=(0.0, 0.0, 2.5), name="R")
    b = FloatingBeam3D(beam, reference="chord", strain="linear", position=(0.0, 0.0, 3.0), name="B")
    law = sf.MotionLaw(lambda t: 0.05 * (1 - np.cos(3 * t)), lambda t: 0.15 * np.sin(3 * t),
                       lambda t: 0.45 * np.cos(3 * t))
    cons = [sf.Weld3D(a.point(0.0)),
            sf.Cylindrical(a.point(2.0), r.point((0.0, 0.0, -0.5)), axis=(0, 1, 0)),
            sf.TranslationDriver(r.point((0.0, 0.0, -0.5)), a.point(2.0), axis=(0, 1, 0), law=law),
            sf.Universal(r.point((0.0, 0.0, 0.5)), b.point(0.0), axis_a=(1, 0, 0), axis_b=(0, 1, 0)),
            sf.Distance3D(b.point(2.0), a.point(1.0))]
    return sf.Scene([a, r, b], cons, [sf.Gravity((-9.81, 0.0, 0.0))], name="floating-frame joints")
