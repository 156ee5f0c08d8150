#!/usr/bin/env python3
"""Apply the bugs named in tests/tests/principled.rs to core/src/bsdf/principled.rs one
at a time, run that test file, log which tests fail (target/inject/log.txt), restore.

    scripts/principled-inject.py [BUG NUMBERS...]
"""
import subprocess, shutil, os, sys
os.chdir(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
os.makedirs("target/inject", exist_ok=True)
src='core/src/bsdf/principled.rs'
orig=open(src).read()
shutil.copy(src,'target/inject/principled.rs.orig')
bugs=[
 ("1 clearcoat probability left out of pdf",
  "pdf += (p_spec * p_refl * d_vis + p_cc * self.coat.pdf(h)) * jacobian;",
  "pdf += (p_spec * p_refl * d_vis + 0.0 * p_cc * self.coat.pdf(h)) * jacobian;"),
 ("2 front transmission share (1-F) in pdf",
  "let (p_refl, p_trans) = self.specular_split(c.front, c.f_d);",
  "let (p_refl, p_trans) = self.specular_split(false, c.f_d);"),
 ("3 transmission Jacobian eta not eta^2",
  "let jacobian = c.eta_path * c.eta_path * dot_i.abs() / (denom * denom);",
  "let jacobian = c.eta_path * dot_i.abs() / (denom * denom);"),
 ("4 radiance scale in importance mode",
  "TransportMode::Importance => 1.0,\n                };",
  "TransportMode::Importance => 1.0 / (c.eta_path * c.eta_path),\n                };"),
 ("5 retro-reflection with F_o twice",
  "let f_retro = rr * (f_o + f_i + f_o * f_i * (rr - 1.0));",
  "let f_retro = rr * (f_o + f_o + f_o * f_i * (rr - 1.0));"),
 ("6 anisotropic alphas swapped in G1",
  "let t2 = (self.ax * self.ax * v.x * v.x + self.ay * self.ay * v.y * v.y) / (v.z * v.z);",
  "let t2 = (self.ay * self.ay * v.x * v.x + self.ax * self.ax * v.y * v.y) / (v.z * v.z);"),
 ("7 sampler's refraction threshold uses the reflection share",
  "let (_, p_trans) = self.specular_split(front, fr.f);",
  "let (p_trans, _) = self.specular_split(front, fr.f);"),
]
sel=sys.argv[1:] 
env=dict(os.environ)
try:
  for name,a,b in bugs:
    if sel and name.split()[0] not in sel: continue
    assert orig.count(a)==1, name
    open(src,'w').write(orig.replace(a,b))
    r=subprocess.run(['cargo','test','--release','-p','ember-tests','--test','principled','--','--test-threads','2'],capture_output=True,text=True,env=env)
    out=r.stdout+r.stderr
    fails=[l for l in out.splitlines() if 'panicked' in l or l.startswith('    ') and '::' not in l and l.strip() and l.strip().split()[0] in ('chi2_principled','sample_matches_eval_and_pdf','reciprocity_and_adjoint','sampled_albedo_and_pdf_mass_match_stratified_integrals','metallic_white_is_the_rough_mirror','furnace_bounds')]
    msgs=[l for l in out.splitlines() if ('rejected' in l or 'against' in l or 'vs' in l or 'exceeds' in l or 'only' in l) and len(l)<600]
    with open('target/inject/log.txt','a') as f:
      f.write(f"=== BUG {name}\n"+"\n".join(fails)+"\n"+"\n".join(m[:400] for m in msgs[:8])+"\n"+[l for l in out.splitlines() if 'test result' in l or 'error' in l][:3].__str__()+"\n")
finally:
  open(src,'w').write(orig)
